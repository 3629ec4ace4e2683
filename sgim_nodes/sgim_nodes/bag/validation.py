"""One validation of a run's records, shared by the live nodes, the recorder and every reader.

Why one: a record the live nodes refuse but the bag readers fold (or the reverse) makes a
resumed run, a rebuild or an analysis differ from the run that happened. So every consumer of
records (the nodes, the recorder, rebuild, resume, analysis, replay) asks this module, with
the same limits, and gets the same verdict. Nothing here imports rclpy: a check reads fields
by name, so rclpy messages, rosbags messages and the records of bag.records all pass.

Two kinds of checks:
  `check(topic, record, limits)`  one record alone: sizes, finite numbers, bounds (outcomes and
                                  goals in [-1, 1]^m, actions in [-1, 1]), known codes, a known
                                  teaching-set index, indices within the run's budget;
  `RunValidator`                  a run's records in arrival order: a movement index must be the
                                  run's next one (never a jump ahead), and a second record of
                                  an index is either a re-execution (its `attempt` is higher:
                                  the simulator client retried it) that supersedes the first, or
                                  a duplicate, which is quarantined. Goals follow the same rule.
A refused record is *quarantined*: the caller logs it (topic, index, reason), counts it, and
never folds it into memory or statistics; the bag still holds it, so an audit sees it.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from sgim_nodes.core.environment import PROCESS_CODES, Status
from sgim_nodes.core.teaching import DEMONSTRATION_CONTENTS, GOAL_ONLY, MEANS_AND_GOAL, MEANS_ONLY

BOUND = 1.0  # actions, outcomes, goals and regions live in [-1, 1]^n
# Processes and statuses a published Movement may carry: the evaluator's and a human's
# measuring casts (PROCESS_EVALUATION, PROCESS_DEMONSTRATION) are never published, and an
# invalid action is never executed.
LEARNER_PROCESSES = frozenset(PROCESS_CODES[p] for p in
                              ("goal_directed", "exploration", "imitation", "random"))
RECORDED_STATUSES = frozenset({Status.OK, Status.NO_CONTACT, Status.PHYSICS_FAILURE})
GOAL_MODES = frozenset({1, 2, 3, 4})
RUN_STATES = frozenset({0, 1, 2})
SOURCES = frozenset({"automatic", "human", "web"})  # teacher, human_input, web_teacher
MAX_ATTEMPT = 255  # Movement.attempt is a uint8
LIMITS_KEY = "sgim_validation_limits"  # the recorder's limits, in a bag's custom_data


@dataclass(frozen=True)
class Problem:
    """Why a record is refused: `kind` is counted (metadata.yaml), `detail` is logged."""

    kind: str  # size, non-finite, out-of-bounds, bad-value, unknown-teaching-index,
    #            beyond-budget, jumps-ahead, duplicate, undecodable
    detail: str

    def __str__(self) -> str:
        return self.detail


@dataclass(frozen=True)
class Limits:
    """What a run's records must respect. 0 means unknown (that check is skipped)."""

    action_size: int = 24
    outcome_size: int = 2
    budget: int = 0  # the run's movement budget
    teaching_set_size: int = 0

    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> Limits:
        values = json.loads(text)
        return cls(**{k: int(v) for k, v in values.items() if k in cls.__dataclass_fields__})

    @classmethod
    def for_run(cls, params: Mapping[str, Any]) -> Limits:
        """The limits of a run from its parameters (params.yaml values, or a node's own)."""
        return cls(action_size=int(params.get("action_size", 24)),
                   outcome_size=int(params.get("outcome_size", 2)),
                   budget=int(params.get("movements", 0) or 0),
                   teaching_set_size=teaching_set_size(params.get("teaching_set", "") or None))


def teaching_set_size(path: str | None = None) -> int:
    """Entries of the run's teaching set (the packaged one by default); 0 when unreadable."""
    try:
        from sim_bridge.data_files import load_teaching_set

        return len(load_teaching_set(path).actions)
    except Exception:  # no sim_bridge, or a missing file: the index check is skipped
        return 0


def _values(values: Any) -> np.ndarray:
    try:
        return np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):
        return np.array([np.nan])


def vector_problem(values: Any, size: int, what: str, bound: float | None = BOUND,
                   allow_empty: bool = False, allow_nan: bool = False) -> Problem | None:
    """Why a vector field is unusable, or None."""
    try:  # the common case, fast: the recorder checks every message of a run
        n = len(values)
        if (n == size or (allow_empty and n == 0)) and bound is not None and all(
                -bound <= x <= bound for x in values):
            return None
    except TypeError:
        pass
    v = _values(values)
    if allow_empty and v.size == 0:
        return None
    if v.size != size:
        return Problem("size", f"{what} must have {size} numbers, got {v.size}")
    finite = np.isfinite(v) | (np.isnan(v) if allow_nan else False)
    if not np.all(finite):
        return Problem("non-finite", f"{what} has NaN or infinite numbers")
    if bound is not None and np.any(np.abs(v[~np.isnan(v)]) > bound):
        return Problem("out-of-bounds", f"{what} numbers must lie in [-{bound:g}, {bound:g}], "
                                        f"got {np.round(v, 4).tolist()}")
    return None


def _index_problem(value: Any, what: str, limits: Limits, low: int = 0) -> Problem | None:
    value = int(value)
    if value < low:
        return Problem("bad-value", f"{what} {value} must be >= {low}")
    if limits.budget and value > limits.budget:
        return Problem("beyond-budget", f"{what} {value} is beyond the run's budget of "
                                        f"{limits.budget} movements")
    return None


def _finite(value: Any, what: str, low: float, high: float) -> Problem | None:
    value = float(value)
    if not math.isfinite(value):
        return Problem("non-finite", f"{what} is {value}")
    if not low <= value <= high:
        return Problem("out-of-bounds", f"{what} {value:g} must lie in [{low:g}, {high:g}]")
    return None


def check_movement(m: Any, limits: Limits) -> Problem | None:
    if int(m.process) not in LEARNER_PROCESSES:
        return Problem("bad-value", f"process {int(m.process)} is not a learner process")
    if int(m.status) not in RECORDED_STATUSES:
        return Problem("bad-value", f"status {int(m.status)} is not a recorded status")
    ok = int(m.status) == Status.OK
    return (_index_problem(m.index, "movement index", limits, low=1)
            or (None if int(getattr(m, "attempt", 0)) <= MAX_ATTEMPT
                else Problem("bad-value", f"attempt {int(m.attempt)} > {MAX_ATTEMPT}"))
            or vector_problem(m.action, limits.action_size, "action")
            or (vector_problem(m.outcome, limits.outcome_size, "outcome") if ok else
                vector_problem(m.outcome, 0, "outcome of a failed movement", allow_empty=True))
            or vector_problem(m.goal, limits.outcome_size, "goal", allow_empty=True))


def check_goal(g: Any, limits: Limits) -> Problem | None:
    if int(g.mode) not in GOAL_MODES:
        return Problem("bad-value", f"goal mode {int(g.mode)} is unknown")
    if int(g.region_id) < -1:
        return Problem("bad-value", f"region id {int(g.region_id)} must be >= -1")
    return (_index_problem(g.index, "goal index", limits, low=1)
            or _index_problem(g.movement_index, "movement index", limits)
            or vector_problem(g.point, limits.outcome_size, "goal point"))


def check_competence(c: Any, limits: Limits) -> Problem | None:
    used = int(c.movements_used)
    if used < 1 or (limits.budget and used > limits.budget):
        return Problem("bad-value", f"movements_used {used} must be >= 1 and within the budget")
    return (_index_problem(c.movement_index, "movement index", limits)
            or vector_problem(c.goal, limits.outcome_size, "goal")
            or vector_problem(c.reached, limits.outcome_size, "reached outcome",
                              allow_empty=True)
            or _finite(c.competence, "competence", -1.0, 0.0))


def demonstration_content(d: Any) -> str:
    """What a demonstration shows (Demonstration.content); a record from a bag recorded before
    the field existed has none, and showed both (the paper's SGIM-D)."""
    return str(getattr(d, "content", MEANS_AND_GOAL))


def check_demonstration(d: Any, limits: Limits) -> Problem | None:
    """An empty action and outcome is the automatic teacher's "nothing left to show". Otherwise
    the demonstration shows exactly what its `content` says: both parts (means-and-goal), the
    outcome and no action (goal-only), or the action and no outcome (means-only)."""
    if str(d.source) not in SOURCES:
        return Problem("bad-value", f"source {str(d.source)!r} is not one of "
                                    f"{', '.join(sorted(SOURCES))}")
    content = demonstration_content(d)
    if content not in DEMONSTRATION_CONTENTS:
        return Problem("bad-value", f"content {content!r} is not one of "
                                    f"{', '.join(DEMONSTRATION_CONTENTS)}")
    problem = _index_problem(d.movement_index, "movement index", limits)
    if problem:
        return problem
    n_action, n_outcome = len(_values(d.action)), len(_values(d.outcome))
    if n_action == 0 and n_outcome == 0:
        return None
    k = int(d.teaching_set_index)
    if k < -1 or (limits.teaching_set_size and k >= limits.teaching_set_size):
        size = limits.teaching_set_size
        return Problem("unknown-teaching-index",
                       f"teaching-set index {k} is not -1 nor an entry of the teaching set"
                       + (f" (0..{size - 1})" if size else ""))
    if int(d.index) < 1:
        return Problem("bad-value", f"demonstration index {int(d.index)} must be >= 1")
    if content == GOAL_ONLY and n_action:
        return Problem("bad-value", f"a goal-only demonstration shows no action, got {n_action} "
                                    "numbers")
    if content == MEANS_ONLY and n_outcome:
        return Problem("bad-value", f"a means-only demonstration shows no outcome, got "
                                    f"{n_outcome} numbers")
    return ((None if content == GOAL_ONLY else
             vector_problem(d.action, limits.action_size, "demonstrated action"))
            or (None if content == MEANS_ONLY else
                vector_problem(d.outcome, limits.outcome_size, "demonstrated outcome")))


def check_help_request(h: Any, limits: Limits) -> Problem | None:
    """A learner's ask (HelpRequest): a 1-based index, a count within the budget (it asks
    before a movement, so below it), and the goal it asks about."""
    if int(h.index) < 1:
        return Problem("bad-value", f"help request index {int(h.index)} must be >= 1")
    problem = _index_problem(h.movement_index, "movement index", limits)
    if problem is None and limits.budget and int(h.movement_index) >= limits.budget:
        problem = Problem("beyond-budget", f"an ask at movement {int(h.movement_index)}: the "
                                           f"budget of {limits.budget} is spent")
    return problem or vector_problem(h.goal, limits.outcome_size, "asked goal")


def check_evaluation(e: Any, limits: Limits) -> Problem | None:
    """`reached` may hold land touch-downs outside [-1, 1]^m, or NaN when nothing came down."""
    size = int(e.outcome_size)
    if size != limits.outcome_size:
        return Problem("size", f"outcome_size {size}, expected {limits.outcome_size}")
    goals, reached, distances = _values(e.goals), _values(e.reached), _values(e.distances)
    n = len(distances)
    if n < 1 or len(goals) != n * size or len(reached) != n * size:
        return Problem("size", f"{len(goals)} goal numbers, {len(reached)} reached numbers and "
                               f"{n} distances do not make {n} goals of size {size}")
    if np.any(np.isinf(reached)):
        return Problem("non-finite", "reached has infinite numbers")
    if not np.all(np.isfinite(distances)) or np.any(distances < 0):
        return Problem("non-finite", "distances must be finite and >= 0")
    mean = float(e.mean_distance)
    if not math.isfinite(mean) or abs(mean - float(distances.mean())) > 1e-6 * max(1.0, mean):
        return Problem("bad-value", f"mean_distance {mean} is not the mean of its distances")
    return (_index_problem(e.movement_index, "movement index", limits)
            or vector_problem(goals, n * size, "benchmark goals"))


def check_run_status(s: Any, limits: Limits) -> Problem | None:
    from sgim_nodes.core.learners import LEARNER_NAMES

    if int(s.state) not in RUN_STATES:
        return Problem("bad-value", f"state {int(s.state)} is unknown")
    if str(s.learner) not in LEARNER_NAMES:
        return Problem("bad-value", f"learner {str(s.learner)!r} is unknown")
    total = int(s.total_movements)
    if total < 1 or (limits.budget and total != limits.budget):
        return Problem("bad-value", f"total_movements {total} is not the run's budget "
                                    f"{limits.budget or '(>= 1)'}")
    if int(s.movement_index) > total:
        return Problem("beyond-budget", f"movement index {int(s.movement_index)} is beyond "
                                        f"total_movements {total}")
    return None


def check_region_map(r: Any, limits: Limits) -> Problem | None:
    problem = _index_problem(r.movement_index, "movement index", limits)
    if problem:
        return problem
    if not len(r.regions):
        return Problem("size", "a region map without regions")
    seen: set[int] = set()
    for region in r.regions:
        rid, parent = int(region.id), int(region.parent_id)
        if rid in seen or (parent != -1 and parent not in seen):
            return Problem("bad-value", f"region {rid}: duplicate id or parent {parent} unknown")
        seen.add(rid)
        problem = (vector_problem(region.lower, limits.outcome_size, f"region {rid} lower")
                   or vector_problem(region.upper, limits.outcome_size, f"region {rid} upper"))
        if problem:
            return problem
        # Both are finite vectors of the outcome size now: plain Python compares them faster
        # than numpy, and a map of hundreds of regions is checked at every attempted goal.
        if any(low > high for low, high in zip(region.lower, region.upper, strict=True)):
            return Problem("bad-value", f"region {rid}: lower corner above upper corner")
        if not math.isfinite(float(region.interest)):
            return Problem("non-finite", f"region {rid}: interest is {float(region.interest)}")
    return None


CHECKS = {
    "movements": check_movement,
    "goals": check_goal,
    "competences": check_competence,
    "demonstrations": check_demonstration,
    "demonstrations_taken": check_demonstration,
    "help_requests": check_help_request,
    "evaluations": check_evaluation,
    "run_status": check_run_status,
    "region_map": check_region_map,
}


def check(topic: str, record: Any, limits: Limits) -> Problem | None:
    """Why one record of `topic` (full name or last component) is unusable, or None."""
    name = topic.rsplit("/", 1)[-1]
    checker = CHECKS.get(name)
    if checker is None:
        return None
    try:
        return checker(record, limits)
    except (AttributeError, TypeError, ValueError, OverflowError) as error:
        return Problem("bad-value", f"unreadable {name} record: {error}")


def record_index(topic: str, record: Any) -> int:
    """The index a log line names: the movement's own, a goal's, else its movement count."""
    name = topic.rsplit("/", 1)[-1]
    for attribute in (("index",) if name in ("movements", "goals") else ()) + (
            "movement_index", "index", "goal_index"):
        value = getattr(record, attribute, None)
        if value is not None:
            try:
                return int(value)
            except (TypeError, ValueError):
                continue
    return -1


@dataclass
class Verdict:
    """What to do with a record: fold it (`ok`), replace the latest one (`supersedes`), or
    quarantine it (`problem`)."""

    problem: Problem | None = None
    supersedes: bool = False

    @property
    def ok(self) -> bool:
        return self.problem is None


class IndexSequence:
    """A run's own count of something indexed 1, 2, 3, ... (movements, goals).

    The next record must carry count + 1. A second record of the latest index is accepted
    only as a re-execution, with a higher `attempt` than the record it supersedes (the
    simulator client retries an unanswered movement with the same index and attempt + 1); any
    other repeat is a duplicate, and an index beyond count + 1 jumps ahead of the run.
    """

    def __init__(self, what: str, count: int = 0) -> None:
        self.what = what
        self.count = count
        self.latest_attempt = 0
        self._resync = False

    def resync(self) -> None:
        """Records may be missing before the next one (a damaged part of a bag was skipped):
        accept its index, if it moves forward, as the new count."""
        self._resync = True

    def admit(self, index: int, attempt: int = 0) -> Verdict:
        index, attempt = int(index), int(attempt)
        if index == self.count + 1 or (self._resync and index > self.count):
            self.count, self.latest_attempt, self._resync = index, attempt, False
            return Verdict()
        if index == self.count and attempt > self.latest_attempt:
            self.latest_attempt = attempt
            return Verdict(supersedes=True)
        if index <= self.count:
            return Verdict(Problem("duplicate", f"{self.what} {index} again (attempt "
                                                f"{attempt}), not a re-execution of the latest "
                                                f"{self.what} {self.count}"))
        return Verdict(Problem("jumps-ahead", f"{self.what} index {index} jumps ahead of the "
                                              f"run's count {self.count}"))


@dataclass(frozen=True)
class Quarantined:
    """A refused record, for logs and metadata."""

    topic: str
    index: int
    problem: Problem
    time_ns: int = 0

    def __str__(self) -> str:
        return f"{self.topic} record {self.index} quarantined: {self.problem.detail}"


@dataclass
class RunValidator:
    """Validates a run's records in arrival order, as the recorder sees them and the readers
    read them; keeps the quarantine and the superseded records for reports."""

    limits: Limits = field(default_factory=Limits)
    movement_count: int = 0
    goal_count: int = 0
    quarantined: list[Quarantined] = field(default_factory=list)
    superseded: list[int] = field(default_factory=list)  # movement indices re-executed

    def __post_init__(self) -> None:
        self.movements = IndexSequence("movement", self.movement_count)
        self.goals = IndexSequence("goal", self.goal_count)

    def resync(self) -> None:
        self.movements.resync()
        self.goals.resync()

    def admit(self, topic: str, record: Any, time_ns: int = 0) -> Verdict:
        name = topic.rsplit("/", 1)[-1]
        problem = check(name, record, self.limits)
        verdict = Verdict(problem)
        if problem is None and name == "movements":
            verdict = self.movements.admit(record.index, getattr(record, "attempt", 0))
            if verdict.supersedes:
                self.superseded.append(int(record.index))
        elif problem is None and name == "goals":
            verdict = self.goals.admit(record.index)
        if verdict.problem is not None:
            self.quarantine(name, record_index(name, record), verdict.problem, time_ns)
        return verdict

    def quarantine(self, topic: str, index: int, problem: Problem, time_ns: int = 0) -> None:
        self.quarantined.append(Quarantined(topic, index, problem, time_ns))

    def counts(self) -> dict[str, dict[str, int]]:
        """Quarantined records per topic and kind, as metadata.yaml holds them."""
        counter = Counter((q.topic, q.problem.kind) for q in self.quarantined)
        out: dict[str, dict[str, int]] = {}
        for (topic, kind), n in sorted(counter.items()):
            out.setdefault(topic, {})[kind] = n
        return out


def summarise(quarantined: list[Quarantined], limit: int = 5) -> list[str]:
    """Log lines: the first `limit` records in full, then one line of counts."""
    lines = [str(q) for q in quarantined[:limit]]
    if len(quarantined) > limit:
        counter = Counter(f"{q.topic} ({q.problem.kind})" for q in quarantined[limit:])
        lines.append(f"... and {len(quarantined) - limit} more: "
                     + ", ".join(f"{n} {what}" for what, n in counter.most_common()))
    return lines


class LiveGate:
    """What a live node does with each record it receives: the same checks as every reader,
    the refusal logged with topic, index and reason (the first `log_limit`, then every 100th),
    and a count. For movements, the run's own count (IndexSequence) decides duplicates and
    jumps, as the readers decide them."""

    def __init__(self, log: Any, limits: Limits, movement_count: int = 0,
                 log_limit: int = 20) -> None:
        self.log = log  # called with one line (e.g. a node logger's .error)
        self.limits = limits
        self.movements = IndexSequence("movement", movement_count)
        self.quarantined = 0
        self.log_limit = log_limit

    def check(self, topic: str, record: Any) -> Problem | None:
        """None when the record may be used; else the problem, already logged."""
        problem = check(topic, record, self.limits)
        if problem is not None:
            self._refuse(topic, record, problem)
        return problem

    def admit_movement(self, record: Any) -> Verdict:
        """A movement: checked, then placed in the run's count (new, re-execution, refused)."""
        problem = check("movements", record, self.limits)
        verdict = Verdict(problem) if problem else self.movements.admit(
            record.index, getattr(record, "attempt", 0))
        if verdict.problem is not None:
            self._refuse("movements", record, verdict.problem)
        return verdict

    def _refuse(self, topic: str, record: Any, problem: Problem) -> None:
        self.quarantined += 1
        n = self.quarantined
        if n <= self.log_limit or n % 100 == 0:
            self.log(f"{topic} record {record_index(topic, record)} quarantined: "
                     f"{problem.detail} (ignored; {n} so far)")
