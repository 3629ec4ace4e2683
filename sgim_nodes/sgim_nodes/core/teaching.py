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

Each turn's judgement is kept (issue 31): ``Teacher.decide`` returns a ``Turn`` holding one
``Check`` per teaching goal (the goal, the action the learner's inverse model gave, where the
teacher's world landed it or the learner's own outcome nearest it, the distance, the tolerance,
the verdict) and what it showed. The graph's teacher publishes them (TeacherCheck on
``teacher_checks``) and the runner writes them, so that an auditor redoes every turn from its
checks alone: ``eligible`` gives the entries the teacher drew among, from the distances only.

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
from .environment import Environment, Status
from .evaluator import landing_point
from .repeatable_casts import RepeatableCasts, goal_key

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


@dataclass(frozen=True)
class Cast:
    """One cast of the ``ability`` rule: the action the learner's inverse model gave for a goal,
    the cast's status in the teacher's world, where it came down (None: never) and how far
    from the goal (inf when it never came down)."""

    action: np.ndarray
    status: int
    landed: np.ndarray | None
    distance: float


class CastMeasure:
    """The ``ability`` rule's measure: called with a goal, how far from it the action
    ``inverse`` gives for it lands when cast in ``world`` (the teacher's own); ``cast`` keeps
    the whole cast, for the turn's checks. A cast that comes down on land is measured to its
    touch-down, as the evaluator measures it; one that never comes down is infinitely far."""

    def __init__(self, inverse: Callable[[np.ndarray], np.ndarray],
                 world: Environment | RepeatableCasts) -> None:
        self.inverse = inverse
        # The teacher's casts outlive one turn (the runner and the node keep one
        # RepeatableCasts): an answer unchanged since the last turn is not cast again.
        self.casts = world if isinstance(world, RepeatableCasts) else RepeatableCasts(world)

    def cast(self, goal: np.ndarray) -> Cast:
        action = np.asarray(self.inverse(goal), dtype=float)
        result = self.casts.execute(goal_key(goal), action)
        point = landing_point(result)
        distance = np.inf if point is None else portable.norm(point - goal)
        return Cast(action, int(result.status), point, distance)

    def __call__(self, goal: np.ndarray) -> float:
        return self.cast(goal).distance


# The learner's progress, as either its reached outcomes (K, m) or a callable giving the
# distance from a goal to the learner's closest reached outcome (a CastMeasure under the
# ``ability`` rule).
Reached = np.ndarray | Callable[[np.ndarray], float]


@dataclass(frozen=True)
class Check:
    """One teaching goal judged at one turn: enough to redo the verdict without the learner or
    the teacher's world (``distance <= tolerance``; TeacherCheck.msg says it for the bag).

    ``ability``: ``action`` is what the learner's inverse model gave, ``status`` and ``landed``
    the cast's in the teacher's world. ``own-movements``: no cast (``action`` None, ``status``
    OK); ``landed`` is the learner's own outcome nearest the goal among ``own_outcomes`` of
    them, recomputable from the run's movements. ``landed`` None: nothing came down."""

    index: int  # row of the teaching set
    goal: np.ndarray
    distance: float
    tolerance: float
    action: np.ndarray | None = None
    status: int = Status.OK
    landed: np.ndarray | None = None
    own_outcomes: int = 0

    @property
    def reached(self) -> bool:
        """The verdict, as the teacher decides it (a goal is unreached when farther)."""
        return not self.distance > self.tolerance

    def to_dict(self) -> dict:
        """Plain JSON (the runner's "teacher_check" records): an infinite distance is null."""
        def vec(x: np.ndarray | None) -> list[float] | None:
            return None if x is None else [float(v) for v in np.asarray(x).ravel()]

        return {"teaching_index": self.index, "goal": vec(self.goal), "action": vec(self.action),
                "status": int(self.status), "landed": vec(self.landed),
                "own_outcomes": self.own_outcomes,
                "distance": float(self.distance) if np.isfinite(self.distance) else None,
                "tolerance": float(self.tolerance), "reached": self.reached}


@dataclass(frozen=True)
class Turn:
    """One decision of the teacher: every check it made, in teaching-set order, what it shows
    (None: it is silent, every goal reached) and the goal a learner asked about, if any."""

    checks: tuple[Check, ...]
    demonstration: Demonstration | None
    asked: np.ndarray | None = None

    @property
    def chosen(self) -> int:
        """The teaching-set row shown, -1 when silent."""
        return -1 if self.demonstration is None else self.demonstration.index


def eligible(distances: np.ndarray, tolerance: float, choice: str,
             goals: np.ndarray | None = None, asked: np.ndarray | None = None) -> np.ndarray:
    """The teaching-set rows a turn draws among (at random, with the teacher's stream), from
    its checks alone: the unreached ones (``distance > tolerance``), narrowed by ``choice``
    (the farthest or nearest), or, answering an ask about ``asked``, to those whose goal lies
    nearest it. Empty: the teacher is silent. ``distances`` and ``goals`` in teaching-set
    order, every row of the set."""
    d = np.asarray(distances, dtype=float)
    candidates = np.flatnonzero(d > tolerance)
    if len(candidates) == 0:
        return candidates
    if asked is not None:
        gap = np.linalg.norm(np.asarray(goals, dtype=float)[candidates]
                             - np.asarray(asked, dtype=float), axis=1)
        return candidates[gap == gap.min()]
    if check_choice(choice) == FARTHEST_UNREACHED:
        return candidates[d[candidates] == d[candidates].max()]
    if choice == NEAREST_UNREACHED:
        return candidates[d[candidates] == d[candidates].min()]
    return candidates


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

    def judge(self, reached: Reached) -> tuple[Check, ...]:
        """One check per teaching goal, in order: the distances of ``distances``, with what
        they were measured to (a CastMeasure's casts, the nearest reached outcome)."""
        if isinstance(reached, CastMeasure):
            casts = [reached.cast(y) for y in self.outcomes]
            return tuple(Check(i, y, c.distance, self.tolerance, c.action, c.status, c.landed)
                         for i, (y, c) in enumerate(zip(self.outcomes, casts, strict=True)))
        if callable(reached):
            return tuple(Check(i, y, float(reached(y)), self.tolerance)
                         for i, y in enumerate(self.outcomes))
        r = np.asarray(reached, dtype=float).reshape(-1, self.outcomes.shape[1])
        if len(r) == 0:
            return tuple(Check(i, y, np.inf, self.tolerance)
                         for i, y in enumerate(self.outcomes))
        # As distances() computes them, bit for bit: the choice compares them for ties.
        d = np.sqrt(((self.outcomes[:, None, :] - r[None, :, :]) ** 2).sum(-1))
        nearest = d.argmin(1)
        return tuple(Check(i, y, float(d[i, j]), self.tolerance, landed=r[j].copy(),
                           own_outcomes=len(r))
                     for i, (y, j) in enumerate(zip(self.outcomes, nearest, strict=True)))

    def decide(self, reached: Reached, asked: np.ndarray | None = None) -> Turn:
        """A turn: every goal judged, then the demonstration ``eligible`` allows, drawn at
        random (None if every goal is reached). ``asked``: the goal a learner asked about
        (help_request.py), which narrows the draw to the entries nearest it instead of
        ``choice``."""
        checks = self.judge(reached)
        asked = None if asked is None else np.asarray(asked, dtype=float)
        candidates = eligible(np.array([c.distance for c in checks]), self.tolerance,
                              self.choice, self.outcomes, asked)
        if len(candidates) == 0:
            return Turn(checks, None, asked)
        i = int(self.rng.choice(candidates))
        return Turn(checks, Demonstration(i, self.actions[i].copy(), self.outcomes[i].copy()),
                    asked)

    def choose(self, reached: Reached) -> Demonstration | None:
        """An unreached demonstration picked by ``choice``, or None if every goal is
        reached."""
        return self.decide(reached).demonstration

    def answer(self, goal: np.ndarray, reached: Reached) -> Demonstration | None:
        """A learner asked for help with ``goal`` (help_request.py): the unreached teaching
        entry whose outcome lies nearest it (ties at random), or None if every goal is
        reached."""
        return self.decide(reached, goal).demonstration


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
                  world: Environment | RepeatableCasts) -> CastMeasure:
    """The ``ability`` rule's measure (CastMeasure): goal -> how far from it the action
    ``inverse`` gives for it lands when cast in ``world`` (the teacher's own)."""
    return CastMeasure(inverse, world)


def learner_progress(rule: str, inverse: Callable[[np.ndarray], np.ndarray],
                     own_outcomes: Callable[[], np.ndarray],
                     world: Environment | RepeatableCasts | None) -> Reached:
    """What ``Teacher.choose`` judges on under ``rule``: the inverse model's casts in the
    teacher's ``world`` (ability), or the outcomes of the learner's own movements."""
    if check_rule(rule) == OWN_MOVEMENTS:
        return own_outcomes()
    if world is None:
        raise ValueError("the 'ability' rule needs the teacher's own world to cast in")
    return cast_distance(inverse, world)
