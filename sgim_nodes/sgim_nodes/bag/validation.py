"""One validation of a run's records, shared by the live nodes, the recorder and every reader.

Why one: a record the live nodes refuse but the bag readers fold (or the reverse) makes a
resumed run, a rebuild or an analysis differ from the run that happened. So every consumer of
records (the nodes, the recorder, rebuild, resume, analysis, replay) asks this module, with
the same limits, and gets the same verdict. Nothing here imports rclpy: a check reads fields
by name, so rclpy messages, rosbags messages and the records of bag.records all pass.

Two kinds of checks:
  `check(topic, record, limits)`  one record alone (record_checks.py): sizes, finite numbers,
                                  bounds (outcomes and goals in [-1, 1]^m, actions in
                                  [-1, 1]), known codes, a known teaching-set index, indices
                                  within the run's budget;
  `RunValidator`                  a run's records in arrival order: a movement index must be the
                                  run's next one (never a jump ahead), and a second record of
                                  an index is either a re-execution (its `attempt` is higher:
                                  the simulator client retried it) that supersedes the first, or
                                  a duplicate, which is quarantined. Goals follow the same rule.
A refused record is *quarantined*: the caller logs it (topic, index, reason), counts it, and
never folds it into memory or statistics; the bag still holds it, so an audit sees it.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from sgim_nodes.bag.record_checks import Limits, Problem, check


def record_index(topic: str, record: Any) -> int:
    """The index a log line names: the movement's own, a goal's, else its movement count."""
    name = topic.rsplit("/", 1)[-1]
    for attribute in (("index",) if name in ("movements", "goals") else ()) + (
            "movement_index", "index", "goal_index"):
        value = getattr(record, attribute, None)
        if value is not None:
            try:
                return int(value)
            except (TypeError, ValueError, OverflowError):  # OverflowError: an infinity
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
