"""Evaluation: how well the learner's inverse model reaches a fixed set of benchmark goals.

For each goal the inverse model's action (no exploration, no Nelder-Mead, no learning) is
executed in the evaluator's OWN environment instance, so that evaluation neither counts as a
movement nor disturbs the training world's state or random stream.  Distances are Euclidean in
outcome units.  A movement without an outcome that still came down somewhere (the fishing
hook on land: its result's ``touchdown``) is measured to that point, which is how far from the
goal the hook really came; only an execution with no touch-down at all (a physics failure) is
reported in ``failed`` and counted at ``failure_distance`` (the diagonal of the world's outcome
box by default: worse than any real outcome) in the mean.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import portable
from .environment import Environment, ResultLike, is_success
from .repeatable_casts import RepeatableCasts, goal_key

# The evaluator's world gets the run's seed plus this, so its noise stream is the same in the
# single-process runner and in the graph's evaluator node, and independent of the learner's.
EVALUATION_SEED_OFFSET = 1_000_003


def landing_point(result: ResultLike) -> np.ndarray | None:
    """Where an execution came down: its outcome, else its touch-down (the fishing hook on
    land), else None (a physics failure)."""
    point = result.outcome if is_success(result) else getattr(result, "touchdown", None)
    return None if point is None else np.asarray(point, dtype=float)


@dataclass(frozen=True)
class EvaluationResult:
    mean_distance: float
    distances: np.ndarray  # (N,)
    failed: np.ndarray  # (N,) bool
    reached: np.ndarray | None = None  # (N, m) outcomes, NaN rows for failed executions

    def to_dict(self) -> dict:
        return {"mean_distance": self.mean_distance,
                "distances": [float(d) for d in self.distances],
                "n_failed": int(self.failed.sum())}


class Evaluator:
    """Holds the benchmark goals and its own environment; each goal's cast has its own noise
    (repeatable_casts.py), so an answer unchanged since the last evaluation is not cast again."""

    def __init__(self, env: Environment, goals: np.ndarray,
                 failure_distance: float | None = None) -> None:
        self.env = env
        self.casts = RepeatableCasts(env)
        self.goals = np.asarray(goals, dtype=float)
        if failure_distance is None:
            scale = getattr(env, "scale", None)
            failure_distance = (scale.diagonal if scale is not None
                                else 2.0 * np.sqrt(self.goals.shape[1]))
        self.failure_distance = float(failure_distance)

    def evaluate(self, inverse: Callable[[np.ndarray], np.ndarray]) -> EvaluationResult:
        """``inverse`` maps a goal to an action (e.g. ``learner.inverse``)."""
        dist = np.empty(len(self.goals))
        failed = np.zeros(len(self.goals), dtype=bool)
        reached = np.full(self.goals.shape, np.nan)
        for i, goal in enumerate(self.goals):
            point = landing_point(self.casts.execute(goal_key(goal), inverse(goal)))
            if point is not None:
                reached[i] = point
                dist[i] = portable.norm(reached[i] - goal)
            else:
                failed[i] = True
                dist[i] = self.failure_distance
        return EvaluationResult(float(dist.mean()), dist, failed, reached)
