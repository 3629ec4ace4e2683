"""The checks of one record alone, shared by the live nodes, the recorder and every reader.

`check(topic, record, limits)` says why one record is unusable, or None: sizes, finite
numbers, bounds (outcomes and goals in [-1, 1]^m, actions in [-1, 1]), known codes, a known
teaching-set index, indices within the run's budget. `Limits` are what a run's records must
respect (the recorder stores them in its bag). Nothing here imports rclpy: a check reads
fields by name, so rclpy messages, rosbags messages and the records of bag.records all pass.
The checks of a run's records in arrival order (duplicates, jumps, re-executions) are in
validation.py, which applies these first.
"""
from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from sgim_nodes.core.environment import PROCESS_CODES, Status
from sgim_nodes.core.strategies import TEACHER_NAME
from sgim_nodes.core.teaching import (
    ABILITY,
    DEMONSTRATION_CONTENTS,
    GOAL_ONLY,
    MEANS_AND_GOAL,
    MEANS_ONLY,
    REACHED_RULES,
    TEACHER_CHOICES,
)
from sgim_ros import record_key
from sgim_ros.record_key import SIGNS_COMPETENCES, SIGNS_MOVEMENTS

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
EXPERT_SOURCE = "expert:"
"""An SGIM-ACTS expert's demonstrations have source "expert:NAME" (teacher/expert_node.py)."""
MAX_ATTEMPT = 255  # Movement.attempt is a uint8
LIMITS_KEY = "sgim_validation_limits"  # the recorder's limits, in a bag's custom_data

STRATEGY_NAME = re.compile(rf"autonomous|(mimicry|emulation):(?:{TEACHER_NAME.pattern})")
"""A Goal's or Competence's strategy (core/strategies.py Strategy.name)."""


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
    """What a run's records must respect. 0 means unknown (that check is skipped).

    ``record_key``: the run's secret with which its simulator signs every movement
    (sgim_ros/record_key.py); a live node takes it from the environment the launcher gives it,
    a reader from the run's folder; "" (a run made without one) skips the check. It never
    goes into to_json: the recorder writes the limits into the bag's metadata."""

    action_size: int = 24
    outcome_size: int = 2
    budget: int = 0  # the run's movement budget
    teaching_set_size: int = 0
    record_key: str = field(default_factory=record_key.from_environment, repr=False,
                            compare=False)
    # Which records the run signs (sgim_ros/record_key.py): today's nodes sign the teaching
    # records and the competences too; a bag that does not say so was recorded when only
    # movements were signed.
    signing: int = SIGNS_COMPETENCES

    def to_json(self) -> str:
        values = asdict(self)
        values.pop("record_key")
        return json.dumps(values, sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> Limits:
        values = {"signing": SIGNS_MOVEMENTS, **json.loads(text)}
        return cls(**{k: int(v) for k, v in values.items()
                      if k in cls.__dataclass_fields__ and k != "record_key"})

    @classmethod
    def for_run(cls, params: Mapping[str, Any]) -> Limits:
        """The limits of a run from its parameters (params.yaml values, or a node's own)."""
        return cls(action_size=int(params.get("action_size", 24)),
                   outcome_size=int(params.get("outcome_size", 2)),
                   budget=int(params.get("movements", 0) or 0),
                   teaching_set_size=teaching_set_size(params.get("teaching_set", "") or None),
                   signing=SIGNS_MOVEMENTS)  # a reader's guess: the older rule


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
            or vector_problem(m.goal, limits.outcome_size, "goal", allow_empty=True)
            or _signature_problem(m, limits))


def _signature_problem(m: Any, limits: Limits) -> Problem | None:
    """A movement of a run with a key must carry its simulator's signature: no other
    publisher can make one (sgim_ros/record_key.py)."""
    if not limits.record_key:
        return None
    try:
        if record_key.signed_by(limits.record_key, m):
            return None
    except (TypeError, ValueError, AttributeError):
        pass
    return Problem("unsigned", f"movement {int(m.index)} (attempt {int(getattr(m, 'attempt', 0))})"
                               " is not signed by the run's simulator")


def check_goal(g: Any, limits: Limits) -> Problem | None:
    if int(g.mode) not in GOAL_MODES:
        return Problem("bad-value", f"goal mode {int(g.mode)} is unknown")
    if int(g.region_id) < -1:
        return Problem("bad-value", f"region id {int(g.region_id)} must be >= -1")
    strategy = str(getattr(g, "strategy", ""))
    if strategy and not STRATEGY_NAME.fullmatch(strategy):
        return Problem("bad-value", f"strategy {strategy!r} is not autonomous, mimicry:NAME "
                                    "or emulation:NAME")
    return (_index_problem(g.index, "goal index", limits, low=1)
            or _index_problem(g.movement_index, "movement index", limits)
            or vector_problem(g.point, limits.outcome_size, "goal point"))


def check_competence(c: Any, limits: Limits) -> Problem | None:
    """An attempted goal spent at least one movement, but for SGIM-ACTS's episode whose
    teacher had nothing to show ("none there"): no movement, nothing reached, competence -1."""
    used = int(c.movements_used)
    strategy = str(getattr(c, "strategy", ""))
    none_there = (used == 0 and ":" in strategy and not len(c.reached)
                  and float(c.competence) == -1.0)
    if (used < 1 and not none_there) or (limits.budget and used > limits.budget):
        return Problem("bad-value", f"movements_used {used} must be >= 1 and within the budget"
                                    " (0 only for a social episode without an answer)")
    if strategy and not STRATEGY_NAME.fullmatch(strategy):
        return Problem("bad-value", f"strategy {strategy!r} is not autonomous, mimicry:NAME "
                                    "or emulation:NAME")
    return (_index_problem(c.movement_index, "movement index", limits)
            or vector_problem(c.goal, limits.outcome_size, "goal")
            or vector_problem(c.reached, limits.outcome_size, "reached outcome",
                              allow_empty=True)
            or _finite(c.competence, "competence", -1.0, 0.0))


def demonstration_content(d: Any) -> str:
    """What a demonstration shows (Demonstration.content); a record from a bag recorded before
    the field existed has none, and showed both (the paper's SGIM-D)."""
    return str(getattr(d, "content", MEANS_AND_GOAL))


def expert_source(name: str) -> str:
    return EXPERT_SOURCE + name


def source_problem(source: str) -> Problem | None:
    """A demonstration comes from one of the graph's teachers: SOURCES, or an expert."""
    if source in SOURCES or (source.startswith(EXPERT_SOURCE)
                             and TEACHER_NAME.fullmatch(source.removeprefix(EXPERT_SOURCE))):
        return None
    return Problem("bad-value", f"source {source!r} is not one of {', '.join(sorted(SOURCES))} "
                                f"nor an expert's ('{EXPERT_SOURCE}NAME')")


def check_demonstration(d: Any, limits: Limits) -> Problem | None:
    """An empty action and outcome is the automatic teacher's "nothing left to show". Otherwise
    the demonstration shows exactly what its `content` says: both parts (means-and-goal), the
    outcome and no action (goal-only), or the action and no outcome (means-only)."""
    problem = source_problem(str(d.source))
    if problem:
        return problem
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


ASKABLE_CONTENTS = ("", MEANS_AND_GOAL, GOAL_ONLY)
"""What a HelpRequest may ask to be shown: the teacher's own setting, the action and its
outcome (mimicry) or the outcome only (emulation)."""


def check_help_request(h: Any, limits: Limits) -> Problem | None:
    """A learner's ask (HelpRequest): a 1-based index, a count within the budget (it asks
    before a movement, so below it), the goal it asks about, and, when it names them, a
    teacher's valid name and what it asks to be shown (fields a bag of an older graph lacks)."""
    if int(h.index) < 1:
        return Problem("bad-value", f"help request index {int(h.index)} must be >= 1")
    teacher = str(getattr(h, "teacher", ""))
    if teacher and not TEACHER_NAME.fullmatch(teacher):
        return Problem("bad-value", f"help request to teacher {teacher!r}: not a teacher's "
                                    f"name (a letter, then letters, digits or '_')")
    content = str(getattr(h, "content", ""))
    if content not in ASKABLE_CONTENTS:
        return Problem("bad-value", f"help request asking for {content!r}: ask for "
                                    f"{MEANS_AND_GOAL!r}, {GOAL_ONLY!r} or nothing (the "
                                    f"teacher's own setting)")
    problem = _index_problem(h.movement_index, "movement index", limits)
    if problem is None and limits.budget and int(h.movement_index) >= limits.budget:
        problem = Problem("beyond-budget", f"an ask at movement {int(h.movement_index)}: the "
                                           f"budget of {limits.budget} is spent")
    return problem or vector_problem(h.goal, limits.outcome_size, "asked goal")


def check_teacher_check(c: Any, limits: Limits) -> Problem | None:
    """One teaching goal judged at a teacher's turn (TeacherCheck.msg): a known rule, choice
    and entry of the turn and of the teaching set, at a count before the budget is spent; its
    distance the one from its goal to where it landed (infinite when nothing landed) and its
    verdict the one its distance and tolerance give, so that an auditor's recomputation of the
    turn stands on numbers that agree with each other."""
    rule, choice = str(c.rule), str(c.choice)
    if rule not in REACHED_RULES:
        return Problem("bad-value", f"reached rule {rule!r} is not one of "
                                    f"{', '.join(REACHED_RULES)}")
    if choice not in TEACHER_CHOICES:
        return Problem("bad-value", f"teacher choice {choice!r} is not one of "
                                    f"{', '.join(TEACHER_CHOICES)}")
    entries, k = int(c.entries), int(c.teaching_set_index)
    size = limits.teaching_set_size
    # A turn judges the whole set, or one teacher's part of it when teachers take turns
    # (core/teacher_turns.py): its entries are rows of the set, at most all of them.
    if k < 0 or entries < 1 or (size and (k >= size or entries > size)):
        return Problem("unknown-teaching-index", f"teaching-set index {k} is not an entry of "
                                                 f"a turn of {entries} checks"
                                                 + (f" (the set has {size})" if size else ""))
    problem = _index_problem(c.movement_index, "movement index", limits)
    if problem is None and limits.budget and int(c.movement_index) >= limits.budget:
        problem = Problem("beyond-budget", f"a teacher's turn at movement "
                                           f"{int(c.movement_index)}: the budget of "
                                           f"{limits.budget} is spent")
    if problem:
        return problem
    asked = _values(c.asked_goal)
    if (int(c.help_request) > 0) != (asked.size > 0):
        return Problem("bad-value", "an answer to a help request carries the goal asked "
                                    "about, and a periodic turn none")
    problem = (vector_problem(c.asked_goal, limits.outcome_size, "asked goal", allow_empty=True)
               or vector_problem(c.goal, limits.outcome_size, "goal judged")
               or (vector_problem(c.action, limits.action_size, "inverse model's action")
                   if rule == ABILITY else
                   vector_problem(c.action, 0, "action of an own-movements check",
                                  allow_empty=True))
               or vector_problem(c.landed, limits.outcome_size, "landing point", bound=None,
                                 allow_empty=True))
    if problem:
        return problem
    if int(c.status) not in set(Status):
        return Problem("bad-value", f"status {int(c.status)} is unknown")
    landed = _values(c.landed)
    if int(c.status) == Status.OK and rule == ABILITY and landed.size == 0:
        return Problem("bad-value", "a cast with status OK landed somewhere")
    tolerance, distance = float(c.tolerance), float(c.distance)
    if not math.isfinite(tolerance) or tolerance < 0:
        return Problem("bad-value", f"tolerance {tolerance} must be finite and >= 0")
    if landed.size == 0:
        if distance != math.inf:
            return Problem("bad-value", f"distance {distance} where nothing landed: must be "
                                        "infinite")
    else:
        expected = float(np.sqrt(((landed - _values(c.goal)) ** 2).sum()))
        if not math.isfinite(distance) or abs(distance - expected) > 1e-9 * max(1.0, expected):
            return Problem("bad-value", f"distance {distance} is not the one from the goal to "
                                        f"where it landed ({expected})")
    if bool(c.reached) != (distance <= tolerance):
        return Problem("bad-value", f"verdict reached={bool(c.reached)}, but distance "
                                    f"{distance} and tolerance {tolerance} say otherwise")
    if bool(c.chosen) and bool(c.reached):
        return Problem("bad-value", f"entry {k} is reached: the teacher never shows it")
    return None


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
    from sgim_nodes.core.learner_registry import is_learner

    if int(s.state) not in RUN_STATES:
        return Problem("bad-value", f"state {int(s.state)} is unknown")
    if not is_learner(s.learner):
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
    "teacher_checks": check_teacher_check,
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
        return checker(record, limits) or teaching_signature_problem(name, record, limits)
    except (AttributeError, TypeError, ValueError, OverflowError) as error:
        return Problem("bad-value", f"unreadable {name} record: {error}")


def teaching_signature_problem(name: str, record: Any, limits: Limits) -> Problem | None:
    """A record that teaches the learner, in a run that signs them, must carry the signature
    of the run's node that made it: no other publisher can make one."""
    since = record_key.SIGNED_SINCE.get(name)
    if not limits.record_key or since is None or limits.signing < since:
        return None
    if record_key.teaching_signed_by(limits.record_key, name, record):
        return None
    which = (f"record {int(record.index)}" if hasattr(record, "index")
             else f"record at movement {int(record.movement_index)}")
    return Problem("unsigned", f"{name} {which} is not signed by the run's node that makes it")
