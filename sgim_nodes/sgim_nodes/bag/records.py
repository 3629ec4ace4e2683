"""Plain dataclasses for the records of a run, detached from any message library.

Analysis code should not depend on rosbags' or rclpy's message classes (which differ between
them): the bag reader converts every sgim_msgs message into one of these, with numpy arrays
for the vectors and nanoseconds for the stamps. `time_ns` is when the recorder received the
message, `stamp_ns` the message's own stamp.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sgim_ros.record_key import signature_of


def _vec(values) -> np.ndarray:
    return np.array(values, dtype=float)


def _stamp(stamp) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


@dataclass
class MovementRecord:
    time_ns: int
    stamp_ns: int
    index: int
    process: int
    status: int
    action: np.ndarray
    outcome: np.ndarray
    goal: np.ndarray
    goal_index: int
    attempt: int = 0  # > 0: a re-execution of the index (bags before it was recorded: 0)
    signature: bytes = field(default_factory=bytes)  # the simulator's (sgim_ros/record_key.py)


@dataclass
class GoalRecord:
    time_ns: int
    stamp_ns: int
    index: int
    movement_index: int
    point: np.ndarray
    region_id: int
    mode: int
    strategy: str = ""  # SGIM-ACTS: how it chose to learn toward it; "" for the others


@dataclass
class CompetenceRecord:
    time_ns: int
    stamp_ns: int
    goal_index: int
    movement_index: int
    goal: np.ndarray
    reached: np.ndarray
    competence: float
    movements_used: int
    from_demonstration: bool
    strategy: str = ""  # SGIM-ACTS: the episode's strategy; "" for the others


@dataclass
class RegionRecord:
    id: int
    parent_id: int
    lower: np.ndarray
    upper: np.ndarray
    interest: float
    goal_count: int
    is_leaf: bool
    least_competent_goal: np.ndarray


@dataclass
class RegionMapRecord:
    time_ns: int
    stamp_ns: int
    movement_index: int
    split_count: int
    goal_count: int
    regions: list[RegionRecord]

    @property
    def leaves(self) -> list[RegionRecord]:
        return [r for r in self.regions if r.is_leaf]


@dataclass
class DemonstrationRecord:
    time_ns: int
    stamp_ns: int
    index: int
    movement_index: int
    action: np.ndarray
    outcome: np.ndarray
    teaching_set_index: int
    source: str
    content: str = "means-and-goal"  # Demonstration.content (bags before it: the paper's)
    help_request: int = 0  # the HelpRequest.index it answers; 0: none

    @property
    def shown(self) -> bool:
        """False for the teacher's "nothing left to show" (empty action and outcome)."""
        return bool(len(self.action) or len(self.outcome))

    @property
    def in_memory(self) -> bool:
        """Whether the learner stores it as an (action, outcome) pair: only when shown both
        (means-and-goal); a goal-only or means-only demonstration never enters memory."""
        return bool(len(self.action) and len(self.outcome))


@dataclass
class HelpRequestRecord:
    """The learner asked a teacher for help (timing on-request, or SGIM-ACTS asking one of
    its experts; HelpRequest.msg)."""

    time_ns: int
    stamp_ns: int
    index: int
    movement_index: int
    goal: np.ndarray
    teacher: str = ""  # the expert asked; "": the run's automatic teacher
    content: str = ""  # what it asked to be shown; "": the teacher's own setting


@dataclass
class TeacherCheckRecord:
    """One teaching goal judged at one of the automatic teacher's turns (TeacherCheck.msg):
    what an auditor redoes the turn's decision from (core/teaching.py, eligible)."""

    time_ns: int
    stamp_ns: int
    movement_index: int
    help_request: int
    asked_goal: np.ndarray  # empty at a periodic turn
    rule: str
    choice: str
    entries: int
    teaching_set_index: int
    goal: np.ndarray
    action: np.ndarray  # empty under own-movements
    status: int
    landed: np.ndarray  # empty when nothing came down
    own_outcomes: int
    distance: float  # inf when landed is empty
    tolerance: float
    reached: bool
    chosen: bool

    @property
    def turn(self) -> tuple[int, int]:
        """Which turn it belongs to: (movement count, HelpRequest.index or 0)."""
        return self.movement_index, self.help_request


@dataclass
class EvaluationRecord:
    time_ns: int
    stamp_ns: int
    movement_index: int
    mean_distance: float
    goals: np.ndarray  # (n, outcome_size)
    # (n, outcome_size): the water, or a touch-down on land (it may lie outside [-1, 1]^2);
    # NaN rows only for casts that never came down (Evaluation.msg)
    reached: np.ndarray
    distances: np.ndarray  # (n,)


@dataclass
class RunStatusRecord:
    time_ns: int
    stamp_ns: int
    learner: str
    seed: int
    movement_index: int
    total_movements: int
    state: int
    message: str


@dataclass
class RunRecords:
    """Every valid record of a run, one list per topic, in recording order.

    Readers validate every record (bag/validation.py): what fails is in `quarantined`, never
    in the lists; a movement superseded by its re-execution is replaced in place (its index is
    listed in `superseded`). `topics`: the record topics the bag declares, so that a reader can
    tell "no demonstration was taken" from "a bag older than demonstrations_taken".
    """

    movements: list[MovementRecord] = field(default_factory=list)
    goals: list[GoalRecord] = field(default_factory=list)
    competences: list[CompetenceRecord] = field(default_factory=list)
    region_map: list[RegionMapRecord] = field(default_factory=list)
    demonstrations: list[DemonstrationRecord] = field(default_factory=list)
    demonstrations_taken: list[DemonstrationRecord] = field(default_factory=list)
    help_requests: list[HelpRequestRecord] = field(default_factory=list)
    teacher_checks: list[TeacherCheckRecord] = field(default_factory=list)
    evaluations: list[EvaluationRecord] = field(default_factory=list)
    run_status: list[RunStatusRecord] = field(default_factory=list)
    quarantined: list = field(default_factory=list)  # validation.Quarantined
    superseded: list[int] = field(default_factory=list)
    topics: set[str] = field(default_factory=set)

    def counts(self) -> dict[str, int]:
        return {name: len(getattr(self, name)) for name in RECORD_TYPES}

    @property
    def learner_demonstrations(self) -> list[DemonstrationRecord]:
        """The demonstrations the learner took (its memory holds them): those the arbiter
        republished, or, in a bag recorded before it did, every non-empty one."""
        if "demonstrations_taken" in self.topics or self.demonstrations_taken:
            return self.demonstrations_taken
        return [d for d in self.demonstrations if d.shown]


def _rows(flat, size: int) -> np.ndarray:
    values = _vec(flat)
    size = max(int(size), 1)
    return values.reshape(-1, size) if len(values) % size == 0 else values.reshape(-1, 1)


def _region(m) -> RegionRecord:
    return RegionRecord(int(m.id), int(m.parent_id), _vec(m.lower), _vec(m.upper),
                        float(m.interest), int(m.goal_count), bool(m.is_leaf),
                        _vec(m.least_competent_goal))


def to_record(kind: type, time_ns: int, m) -> object:
    """Convert a deserialised message (rosbags or rclpy) into the record dataclass `kind`."""
    t, s = int(time_ns), _stamp(m.stamp)
    if kind is MovementRecord:
        return MovementRecord(t, s, int(m.index), int(m.process), int(m.status), _vec(m.action),
                              _vec(m.outcome), _vec(m.goal), int(m.goal_index),
                              int(getattr(m, "attempt", 0)),
                              signature_of(m))
    if kind is GoalRecord:
        return GoalRecord(t, s, int(m.index), int(m.movement_index), _vec(m.point),
                          int(m.region_id), int(m.mode), str(getattr(m, "strategy", "")))
    if kind is CompetenceRecord:
        return CompetenceRecord(t, s, int(m.goal_index), int(m.movement_index), _vec(m.goal),
                                _vec(m.reached), float(m.competence), int(m.movements_used),
                                bool(m.from_demonstration), str(getattr(m, "strategy", "")))
    if kind is RegionMapRecord:
        return RegionMapRecord(t, s, int(m.movement_index), int(m.split_count),
                               int(m.goal_count), [_region(r) for r in m.regions])
    if kind is DemonstrationRecord:
        return DemonstrationRecord(t, s, int(m.index), int(m.movement_index), _vec(m.action),
                                   _vec(m.outcome), int(m.teaching_set_index), str(m.source),
                                   str(getattr(m, "content", "means-and-goal")),
                                   int(getattr(m, "help_request", 0)))
    if kind is HelpRequestRecord:
        return HelpRequestRecord(t, s, int(m.index), int(m.movement_index), _vec(m.goal),
                                 str(getattr(m, "teacher", "")), str(getattr(m, "content", "")))
    if kind is TeacherCheckRecord:
        return TeacherCheckRecord(t, s, int(m.movement_index), int(m.help_request),
                                  _vec(m.asked_goal), str(m.rule), str(m.choice),
                                  int(m.entries), int(m.teaching_set_index), _vec(m.goal),
                                  _vec(m.action), int(m.status), _vec(m.landed),
                                  int(m.own_outcomes), float(m.distance), float(m.tolerance),
                                  bool(m.reached), bool(m.chosen))
    if kind is EvaluationRecord:
        return EvaluationRecord(t, s, int(m.movement_index), float(m.mean_distance),
                                _rows(m.goals, m.outcome_size), _rows(m.reached, m.outcome_size),
                                _vec(m.distances))
    if kind is RunStatusRecord:
        return RunStatusRecord(t, s, str(m.learner), int(m.seed), int(m.movement_index),
                               int(m.total_movements), int(m.state), str(m.message))
    raise TypeError(f"no record type {kind!r}")


RECORD_TYPES: dict[str, type] = {
    "movements": MovementRecord,
    "goals": GoalRecord,
    "competences": CompetenceRecord,
    "region_map": RegionMapRecord,
    "demonstrations": DemonstrationRecord,
    "demonstrations_taken": DemonstrationRecord,
    "help_requests": HelpRequestRecord,
    "teacher_checks": TeacherCheckRecord,
    "evaluations": EvaluationRecord,
    "run_status": RunStatusRecord,
}
