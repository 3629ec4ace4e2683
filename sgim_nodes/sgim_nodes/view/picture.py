"""The live picture of a run, as its topics show it: what a person teaching it needs to see.

Where the hook landed and which process cast it, the interest tree's leaves and their interest,
the teaching goals the learner has reached or not, the current goal, the error curve, the
movement count and the budget. The web teacher serves it to a page and the markers node turns
it into MarkerArrays; both feed it messages and read it, nothing here imports ROS.

"Reached" is asked of the teacher's class (core.teaching.Teacher.unreached) on the learner's
landed movements, as a person teaching sees them; the automatic teacher's default rule
(``ability``) casts the learner's inverse model instead, so the two can differ.
Landings only grow: readers ask for what came after the landings they already have, which
keeps a 5000-movement run cheap to follow.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from sgim_nodes.core.environment import PROCESS_CODES
from sgim_nodes.core.teaching import MEANS_AND_GOAL, MEANS_ONLY, Teacher

# Colours shared by the page and the markers (RGB 0-255), one per Movement.PROCESS_* code.
PROCESS_COLOURS: dict[int, tuple[int, int, int]] = {
    PROCESS_CODES["goal_directed"]: (31, 119, 180),  # own goal: blue
    PROCESS_CODES["exploration"]: (255, 127, 14),  # exploration: orange
    PROCESS_CODES["imitation"]: (44, 160, 44),  # imitation: green
    PROCESS_CODES["demonstration"]: (214, 39, 40),  # the teacher's action: red
    PROCESS_CODES["random"]: (127, 127, 127),  # random baseline: grey
}
PROCESS_NAMES: dict[int, str] = {
    PROCESS_CODES["goal_directed"]: "own goal",
    PROCESS_CODES["exploration"]: "exploration",
    PROCESS_CODES["imitation"]: "imitation",
    PROCESS_CODES["demonstration"]: "demonstration",
    PROCESS_CODES["random"]: "random",
}
# Interest 0 .. the highest leaf interest, as viridis stops (matplotlib's, sampled).
INTEREST_STOPS: tuple[tuple[float, tuple[int, int, int]], ...] = (
    (0.0, (68, 1, 84)), (0.25, (59, 82, 139)), (0.5, (33, 145, 140)),
    (0.75, (94, 201, 98)), (1.0, (253, 231, 37)))
REACHED_COLOUR = (46, 204, 64)
UNREACHED_COLOUR = (230, 40, 40)
GOAL_COLOUR = (255, 255, 255)


def interest_colour(fraction: float) -> tuple[int, int, int]:
    """The palette's colour for interest / highest interest in [0, 1]."""
    f = min(1.0, max(0.0, float(fraction))) if np.isfinite(fraction) else 0.0
    for (f0, c0), (f1, c1) in itertools.pairwise(INTEREST_STOPS):
        if f <= f1:
            t = (f - f0) / (f1 - f0)
            return tuple(round(a + t * (b - a)) for a, b in zip(c0, c1, strict=True))
    return INTEREST_STOPS[-1][1]


@dataclass(frozen=True)
class Leaf:
    low: tuple[float, float]
    high: tuple[float, float]
    interest: float


@dataclass
class DemonstrationSeen:
    index: int
    movement_index: int
    outcome: tuple[float, ...]
    teaching_set_index: int
    source: str
    imitated_from: int = 0  # its first imitation movement; 0: not yet
    content: str = MEANS_AND_GOAL  # what it shows (core/teaching.py); means-only: no outcome


@dataclass
class LivePicture:
    """Everything a viewer draws, updated from messages; ``version`` counters tell a reader
    what changed since it last looked."""

    teacher: Teacher  # the automatic teacher's rule and its teaching set
    xs: list[float] = field(default_factory=list)  # landed outcomes, in arrival order
    ys: list[float] = field(default_factory=list)
    processes: list[int] = field(default_factory=list)
    indices: list[int] = field(default_factory=list)
    failed: int = 0  # movements that did not land on water
    count: int = 0  # highest movement index heard
    total: int = 0  # the budget (from run_status; 0 until heard)
    learner: str = ""
    run_state: str = "waiting"  # waiting (no status yet), running, finished, aborted
    run_message: str = ""
    leaves: list[Leaf] = field(default_factory=list)
    regions_version: int = 0
    goal: tuple[float, float] | None = None
    goal_version: int = 0
    evaluations: list[tuple[int, float]] = field(default_factory=list)
    demonstrations: list[DemonstrationSeen] = field(default_factory=list)
    reached: np.ndarray = field(default=None)  # type: ignore[assignment]  # per teaching goal
    teaching_version: int = 0
    _judged_landings: int = -1
    changed_at: float = field(default_factory=time.monotonic)

    def __post_init__(self) -> None:
        if self.reached is None:
            self.reached = np.zeros(len(self.teacher.outcomes), dtype=bool)

    # --- what the topics say --------------------------------------------------------------

    def add_movement(self, index: int, process: int, landed: bool,
                     outcome: Sequence[float], goal: Sequence[float]) -> None:
        self.count = max(self.count, int(index))
        if landed and len(outcome) == 2 and np.all(np.isfinite(outcome)):
            self.xs.append(float(outcome[0]))
            self.ys.append(float(outcome[1]))
            self.processes.append(int(process))
            self.indices.append(int(index))
        else:
            self.failed += 1
        if len(goal) == 2:
            self.set_goal(goal)
        if process == PROCESS_CODES["imitation"]:
            self._note_imitation(int(index), goal)
        self.changed_at = time.monotonic()

    def set_goal(self, point: Sequence[float]) -> None:
        new = (float(point[0]), float(point[1]))
        if new != self.goal:
            self.goal = new
            self.goal_version += 1

    def set_regions(self, leaves: Sequence[Leaf]) -> None:
        self.leaves = list(leaves)
        self.regions_version += 1

    def add_evaluation(self, movement_index: int, mean_distance: float) -> None:
        if not any(m == movement_index for m, _ in self.evaluations):
            self.evaluations.append((int(movement_index), float(mean_distance)))
            self.evaluations.sort()

    def add_demonstration(self, demo: DemonstrationSeen) -> None:
        """Keep a demonstration that shows something: an outcome, or (means-only) an action
        whose outcome the learner will see by imitating it."""
        if len(demo.outcome) == 2 or demo.content == MEANS_ONLY:
            self.demonstrations.append(demo)

    def set_status(self, learner: str, count: int, total: int, state: str, message: str) -> None:
        self.learner, self.total = learner, int(total)
        self.count = max(self.count, int(count))
        self.run_state = state
        if message:
            self.run_message = message

    def _note_imitation(self, index: int, goal: Sequence[float]) -> None:
        """The latest demonstration not yet imitated that this imitation aims at: the one of
        its outcome, or, for an imitation without a goal, a means-only one."""
        for demo in reversed(self.demonstrations):
            if demo.imitated_from:
                break
            aims_at = (np.allclose(demo.outcome, goal) if len(goal) == 2 == len(demo.outcome)
                       else not len(goal) and demo.content == MEANS_ONLY)
            if aims_at:
                demo.imitated_from = index
                break

    # --- what a reader wants ----------------------------------------------------------------

    @property
    def landings(self) -> int:
        return len(self.xs)

    def reached_outcomes(self) -> np.ndarray:
        return np.column_stack([self.xs, self.ys]) if self.xs else np.empty((0, 2))

    def judge_teaching_goals(self) -> bool:
        """Ask the teacher's rule again if landings came since; True when a verdict changed."""
        if self._judged_landings == self.landings:
            return False
        self._judged_landings = self.landings
        reached = np.ones(len(self.teacher.outcomes), dtype=bool)
        reached[self.teacher.unreached(self.reached_outcomes())] = False
        if np.array_equal(reached, self.reached):
            return False
        self.reached = reached
        self.teaching_version += 1
        return True

    def unreached(self) -> list[int]:
        return [int(i) for i in np.flatnonzero(~self.reached)]

    def highest_interest(self) -> float:
        return max((leaf.interest for leaf in self.leaves), default=0.0)

    @property
    def budget_spent(self) -> bool:
        return self.total > 0 and self.count >= self.total

    @property
    def over(self) -> bool:
        return self.run_state in ("finished", "aborted")
