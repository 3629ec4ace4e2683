"""Imitation of a demonstration: a_demo + a_rand with |a_rand| < epsilon, clipped to [-1, 1].

Small variations around the teacher's action explore the neighbourhood of an outcome the
learner may never have found alone.  |a_rand| is bounded in Euclidean norm, which also bounds
every component (the stricter reading of the paper), and clipping to the box can only move the
action closer to a_demo (projection onto a convex set holding a_demo), so the bound survives.
"""

from __future__ import annotations

import numpy as np

from . import portable
from .environment import ResultLike, is_success

IMITATION = "imitation"


def perturb(action: np.ndarray, epsilon: float, rng: np.random.Generator) -> np.ndarray:
    """action + a_rand, a_rand uniform in the open Euclidean ball of radius epsilon, clipped."""
    action = np.asarray(action, dtype=float)
    direction = rng.standard_normal(action.shape)
    norm = portable.norm(direction)
    if norm == 0.0:
        return np.clip(action, -1.0, 1.0)
    radius = epsilon * (1.0 - rng.random()) ** (1.0 / action.size)  # in (0, eps]
    radius = min(radius, np.nextafter(epsilon, 0.0))  # strictly below epsilon
    return np.clip(action + direction / norm * radius, -1.0, 1.0)


class Imitation:
    """Ask/tell process: ``count`` variations of one demonstrated action."""

    def __init__(self, demo_action: np.ndarray, demo_outcome: np.ndarray | None, count: int,
                 epsilon: float, rng: np.random.Generator,
                 start_distance: float = float("inf")) -> None:
        """``start_distance``: memory's distance to the demonstrated outcome before the
        demonstration was stored (the competence of the imitation is measured against it).
        ``demo_outcome`` None: a means-only demonstration (teaching.py), the learner was not
        told where the action lands; the imitation has no goal and no competence."""
        self.demo_action = np.asarray(demo_action, dtype=float)
        self.goal = None if demo_outcome is None else np.asarray(demo_outcome, dtype=float)
        self.count = count
        self.epsilon = epsilon
        self.rng = rng
        self.start_distance = start_distance
        self.movements = 0
        self.best_distance = float("inf")
        self.best_outcome: np.ndarray | None = None
        self.done = count == 0

    def next_action(self) -> tuple[np.ndarray, str]:
        if self.done:
            raise RuntimeError("imitation is finished")
        return perturb(self.demo_action, self.epsilon, self.rng), IMITATION

    def observe(self, action: np.ndarray, result: ResultLike) -> None:
        self.movements += 1
        if is_success(result) and self.goal is not None:
            outcome = np.asarray(result.outcome, dtype=float)
            d = portable.norm(outcome - self.goal)
            if d < self.best_distance:
                self.best_distance, self.best_outcome = d, outcome.copy()
        if self.movements >= self.count:
            self.done = True
