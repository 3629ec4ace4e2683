"""The automatic teacher's logic, without ROS.

The paper (Nguyen et al. 2011, section IV): "the teacher gives a demonstration at constant
frequency, and randomly selects it from a set of demonstrations", "a random demonstration
among the unreached goals", the teacher knowing the learner's state. So every ``period``
movements (P = 150) the teacher gives one demonstration (action, outcome) drawn at random, with
its own seeded Generator, among the teaching-set outcomes the learner has NOT reached.

"Reached" is judged on what the learner can do by itself, never on the stored demonstration
(it is in the learner's memory the moment it is shown: judging on memory made every
demonstrated goal reached at once and the teacher fell silent after about 1000 movements). The
paper's teacher knows the learner's state, so it may ask the learner itself. Two rules
(``REACHED_RULES``):

- ``ability`` (the default): a teaching goal is reached when the learner's inverse model,
  asked for that goal NOW, gives an action whose cast lands within ``tolerance`` of it. The
  teacher casts in its OWN copy of the world (its own noise stream, "teacher-world" in
  random_streams.py): these casts are not learner movements, never enter the learner's memory
  and do not count against the budget, as the evaluator's casts. The inverse model reads the
  learner's whole memory, demonstrations and imitations included, since the cast decides, not
  a stored outcome. A goal reached once by luck but missed by the inverse model stays
  unreached, and a goal the learner can no longer hit is taught again.
- ``own-movements``: a teaching goal is reached once one of the learner's OWN movements
  (goal-directed, exploration or random: ``OWN_PROCESSES``; not the demonstrations, not the
  imitations) has landed within ``tolerance`` of it. One lucky landing suffices, so the
  teacher ran out after 7 to 9 demonstrations in a 5000-movement fishing run (P = 150, 33
  turns).

The tolerance is a multiple of the world's outcome noise (``DEFAULT_TOLERANCE_NOISE``). When
every goal is reached the teacher gives nothing at that turn.

Which unreached goal (``TEACHER_CHOICES``, issue 14; the paper's Section III lists the teacher's
choice among "a random one among the unreached goals", its own, and leaves the others to future
work): ``random-unreached`` (the paper's), ``farthest-unreached`` (the goal the learner's
ability, as measured by the reached rule, lands farthest from: what it can do least) and
``nearest-unreached`` (the closest to being reached: what it almost can do). Ties, e.g. goals
the learner has nothing near yet, are broken at random with the teacher's stream.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import portable
from .environment import Environment
from .evaluator import landing_point

PAPER_PERIOD = 150
OWN_PROCESSES = ("goal_directed", "exploration", "random")
"""Process labels of the movements that show what the learner can do by itself."""
DEFAULT_TOLERANCE_NOISE = 1.0
"""A teaching goal counts as reached within this many units of the world's outcome noise:
closer than the noise, two outcomes cannot be told apart."""
ABILITY = "ability"
OWN_MOVEMENTS = "own-movements"
REACHED_RULES = (ABILITY, OWN_MOVEMENTS)
DEFAULT_REACHED_RULE = ABILITY
RANDOM_UNREACHED = "random-unreached"
FARTHEST_UNREACHED = "farthest-unreached"
NEAREST_UNREACHED = "nearest-unreached"
TEACHER_CHOICES = (RANDOM_UNREACHED, FARTHEST_UNREACHED, NEAREST_UNREACHED)
DEFAULT_TEACHER_CHOICE = RANDOM_UNREACHED
MEANS_AND_GOAL = "means-and-goal"
GOAL_ONLY = "goal-only"
MEANS_ONLY = "means-only"
DEMONSTRATION_CONTENTS = (MEANS_AND_GOAL, GOAL_ONLY, MEANS_ONLY)
DEFAULT_DEMONSTRATION_CONTENT = MEANS_AND_GOAL


@dataclass(frozen=True)
class Demonstration:
    index: int  # row of the teaching set
    action: np.ndarray
    outcome: np.ndarray

    def shown(self, content: str) -> tuple[np.ndarray | None, np.ndarray | None]:
        """(action, outcome) as the learner is given them under ``content``
        (``DEMONSTRATION_CONTENTS``, issue 14; the paper's Section III): both (``means-and-goal``,
        the paper's SGIM-D), the outcome only (``goal-only``: emulation, the learner adopts it
        as a goal and is never told the action), or the action only (``means-only``: the learner
        executes it and observes the outcome itself). What is not shown is None."""
        check_content(content)
        return (None if content == GOAL_ONLY else self.action.copy(),
                None if content == MEANS_ONLY else self.outcome.copy())


# The learner's progress, as either its reached outcomes (K, m) or a callable giving the
# distance from a goal to the learner's closest reached outcome.
Reached = np.ndarray | Callable[[np.ndarray], float]


class Teacher:
    def __init__(self, actions: np.ndarray, outcomes: np.ndarray, rng: np.random.Generator,
                 period: int = PAPER_PERIOD, tolerance: float = 0.05,
                 choice: str = DEFAULT_TEACHER_CHOICE) -> None:
        """``tolerance``: Euclidean distance in outcome units under which a teaching goal
        counts as reached; chosen below the paper's outcome noise 0.073 but above typical
        inverse-model errors on reached points. ``choice``: which unreached goal
        (``TEACHER_CHOICES``)."""
        self.actions = np.asarray(actions, dtype=float)
        self.outcomes = np.asarray(outcomes, dtype=float)
        if len(self.actions) != len(self.outcomes) or len(self.actions) == 0:
            raise ValueError("teaching set needs as many actions as outcomes, at least one")
        if period < 1:
            raise ValueError(f"period must be >= 1, got {period}")
        if tolerance < 0:
            raise ValueError(f"tolerance must be >= 0, got {tolerance}")
        self.rng = rng
        self.period = period
        self.tolerance = tolerance
        self.choice = check_choice(choice)

    def due(self, movements: int) -> bool:
        """True at movements 0, P, 2P, ... (a demonstration before the first movement too,
        so that demo-only has something to vary from the start)."""
        return movements % self.period == 0

    def distances(self, reached: Reached) -> np.ndarray:
        """How far the learner is from each teaching goal (inf: nothing reached at all)."""
        if callable(reached):
            return np.array([float(reached(y)) for y in self.outcomes])
        r = np.asarray(reached, dtype=float).reshape(-1, self.outcomes.shape[1])
        if len(r) == 0:
            return np.full(len(self.outcomes), np.inf)
        return np.sqrt(((self.outcomes[:, None, :] - r[None, :, :]) ** 2).sum(-1)).min(1)

    def unreached(self, reached: Reached) -> np.ndarray:
        """Indices of teaching goals farther than ``tolerance`` from every reached outcome."""
        return np.flatnonzero(self.distances(reached) > self.tolerance)

    def choose(self, reached: Reached) -> Demonstration | None:
        """An unreached demonstration picked by ``choice``, or None if every goal is
        reached."""
        d = self.distances(reached)
        candidates = np.flatnonzero(d > self.tolerance)
        if len(candidates) == 0:
            return None
        if self.choice == FARTHEST_UNREACHED:
            candidates = candidates[d[candidates] == d[candidates].max()]
        elif self.choice == NEAREST_UNREACHED:
            candidates = candidates[d[candidates] == d[candidates].min()]
        i = int(self.rng.choice(candidates))
        return Demonstration(i, self.actions[i].copy(), self.outcomes[i].copy())

    def answer(self, goal: np.ndarray, reached: Reached) -> Demonstration | None:
        """A learner asked for help with ``goal`` (help_request.py): the unreached teaching
        entry whose outcome lies nearest it (ties at random), or None if every goal is
        reached."""
        candidates = self.unreached(reached)
        if len(candidates) == 0:
            return None
        gap = np.linalg.norm(self.outcomes[candidates] - np.asarray(goal, dtype=float), axis=1)
        i = int(self.rng.choice(candidates[gap == gap.min()]))
        return Demonstration(i, self.actions[i].copy(), self.outcomes[i].copy())


def check_choice(choice: str) -> str:
    if choice not in TEACHER_CHOICES:
        raise ValueError(f"unknown teacher choice {choice!r}; choose one of {TEACHER_CHOICES}")
    return choice


def check_content(content: str) -> str:
    if content not in DEMONSTRATION_CONTENTS:
        raise ValueError(f"unknown demonstration content {content!r}; choose one of "
                         f"{DEMONSTRATION_CONTENTS}")
    return content


def check_rule(rule: str) -> str:
    if rule not in REACHED_RULES:
        raise ValueError(f"unknown reached rule {rule!r}; choose one of {REACHED_RULES}")
    return rule


def cast_distance(inverse: Callable[[np.ndarray], np.ndarray],
                  world: Environment) -> Callable[[np.ndarray], float]:
    """The ``ability`` rule's measure: goal -> how far from it the action ``inverse`` gives
    for it lands when cast in ``world`` (the teacher's own). A cast that comes down on land
    is measured to its touch-down, as the evaluator measures it; one that never comes down is
    infinitely far."""
    def distance(goal: np.ndarray) -> float:
        point = landing_point(world.execute(np.asarray(inverse(goal), dtype=float)))
        return np.inf if point is None else portable.norm(point - goal)

    return distance


def learner_progress(rule: str, inverse: Callable[[np.ndarray], np.ndarray],
                     own_outcomes: Callable[[], np.ndarray],
                     world: Environment | None) -> Reached:
    """What ``Teacher.choose`` judges on under ``rule``: the inverse model's casts in the
    teacher's ``world`` (ability), or the outcomes of the learner's own movements."""
    if check_rule(rule) == OWN_MOVEMENTS:
        return own_outcomes()
    if world is None:
        raise ValueError("the 'ability' rule needs the teacher's own world to cast in")
    return cast_distance(inverse, world)
