"""Competence of a goal attempt, measured against what memory already reached near the goal.

The paper's SAGG-RIAC similarity is Sim(y_g, y) = -min(1, D(y_g, y) / D(y_g, y_start)): how much
of the way from the start to the goal the attempt covered. We take y_start to be the outcome
memory held closest to the goal BEFORE the attempt (the best the learner could already do),
not a fixed origin. Why (issue 10, measured in docs/learners.md): with a fixed origin the
competence of a goal depends on where the goal lies, so goals drawn in one region never share a
constant competence and unreachable regions never go quiet; against memory, a goal nothing can
reach gets the constant -1 (no attempt beats memory), a mastered goal 0, and only regions where
attempts really gain on memory change competence over time, which is what the interest reads.

Noise: an attempt that lands within ``success_tolerance`` of the goal (one noise unit by
default) is a full success, and both distances are measured beyond that tolerance, so the
world's noise does not look like progress or regress:

    competence = -min(1, max(0, d - tol) / max(d_start - tol, tol))

with d the attempt's best distance to the goal and d_start memory's before the attempt. An
attempt that does not beat memory (d >= d_start, every unreachable goal once memory holds the
nearest reachable outcome) gets exactly -1; one within the tolerance exactly 0. Only goals
where attempts gain on memory, partly, give other values: the interest of a region (eq. 2)
is then nonzero exactly where the learner is changing what it can do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import portable
from .environment import ResultLike, is_success


def competence(goal: np.ndarray, best_outcome: np.ndarray | None, start_distance: float,
               success_tolerance: float, floor: float | None = None) -> float:
    """In [-1, 0]; -1 when nothing was reached (every movement failed). ``floor`` (default:
    the tolerance) is the smallest reference distance: where memory already lands within the
    noise of the goal, a miss by a noise unit must not count as total failure."""
    if best_outcome is None:
        return -1.0
    d = portable.norm(np.asarray(best_outcome, float) - np.asarray(goal, float))
    excess = max(0.0, d - success_tolerance)
    if excess == 0.0:
        return 0.0
    base = max(start_distance - success_tolerance,
               success_tolerance if floor is None else floor)
    if not math.isfinite(base) or base <= 0.0:
        return -1.0
    return -min(1.0, excess / base)


def start_distance(closest_distance: float, goal: np.ndarray, centre: np.ndarray) -> float:
    """Memory's distance to the goal before an attempt; with an empty memory, the distance
    from the goal to the centre of the outcome box (where a learner with no experience may as
    well be)."""
    if math.isfinite(closest_distance):
        return float(closest_distance)
    return portable.norm(np.asarray(goal, float) - np.asarray(centre, float))


@dataclass
class NearestOutcome:
    """The outcome nearest ``point`` over an episode's successful movements (the first of
    equally near ones): every strategy is measured at the goal the learner chose, whatever
    its movements aimed at. The graph's nodes measure with it too, and a resumed run measures
    the imitations a kill cut."""

    point: np.ndarray
    distance: float = float("inf")
    outcome: np.ndarray | None = None

    def observe(self, result: ResultLike) -> None:
        if is_success(result):
            outcome = np.asarray(result.outcome, dtype=float)
            d = portable.norm(outcome - self.point)
            if d < self.distance:
                self.distance, self.outcome = d, outcome.copy()
