"""The automatic teacher's logic, without ROS.

The paper (Nguyen et al. 2011, section IV): "the teacher gives a demonstration at constant
frequency, and randomly selects it from a set of demonstrations", "a random demonstration
among the unreached goals", the teacher knowing the learner's state. So every ``period``
movements (P = 150) the teacher gives one demonstration (action, outcome) drawn at random, with
its own seeded Generator, among the teaching-set outcomes the learner has NOT reached.

"Reached" is judged on what the learner can do by itself: a teaching goal is reached once one
of the learner's OWN movements (goal-directed, exploration or random: ``OWN_PROCESSES``) lands
within ``tolerance`` of it. Never the stored demonstration (it is in the learner's memory the
moment it is shown, so judging on memory made every demonstrated goal reached at once and the
teacher fell silent after about 1000 movements), and not the imitations either (repeating the
teacher's action is not yet reaching the goal on one's own; the learner has integrated a
demonstration once its own goal-directed movements land there). A demonstrated goal can thus be
shown again until the learner reaches it itself. The tolerance is a multiple of the world's
outcome noise (``DEFAULT_TOLERANCE_NOISE``). When every goal is reached the teacher gives
nothing at that turn.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

PAPER_PERIOD = 150
OWN_PROCESSES = ("goal_directed", "exploration", "random")
"""Process labels of the movements that show what the learner can do by itself."""
DEFAULT_TOLERANCE_NOISE = 1.0
"""A teaching goal counts as reached within this many units of the world's outcome noise:
closer than the noise, two outcomes cannot be told apart."""


@dataclass(frozen=True)
class Demonstration:
    index: int  # row of the teaching set
    action: np.ndarray
    outcome: np.ndarray


# The learner's progress, as either its reached outcomes (K, m) or a callable giving the
# distance from a goal to the learner's closest reached outcome.
Reached = np.ndarray | Callable[[np.ndarray], float]


class Teacher:
    def __init__(self, actions: np.ndarray, outcomes: np.ndarray, rng: np.random.Generator,
                 period: int = PAPER_PERIOD, tolerance: float = 0.05) -> None:
        """``tolerance``: Euclidean distance in outcome units under which a teaching goal
        counts as reached; chosen below the paper's outcome noise 0.073 but above typical
        inverse-model errors on reached points."""
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

    def due(self, movements: int) -> bool:
        """True at movements 0, P, 2P, ... (a demonstration before the first movement too,
        so that demo-only has something to vary from the start)."""
        return movements % self.period == 0

    def unreached(self, reached: Reached) -> np.ndarray:
        """Indices of teaching goals farther than ``tolerance`` from every reached outcome."""
        if callable(reached):
            d = np.array([float(reached(y)) for y in self.outcomes])
        else:
            r = np.asarray(reached, dtype=float).reshape(-1, self.outcomes.shape[1])
            if len(r) == 0:
                return np.arange(len(self.outcomes))
            d = np.sqrt(((self.outcomes[:, None, :] - r[None, :, :]) ** 2).sum(-1)).min(1)
        return np.flatnonzero(d > self.tolerance)

    def choose(self, reached: Reached) -> Demonstration | None:
        """A random unreached demonstration, or None if every goal is reached."""
        candidates = self.unreached(reached)
        if len(candidates) == 0:
            return None
        i = int(self.rng.choice(candidates))
        return Demonstration(i, self.actions[i].copy(), self.outcomes[i].copy())
