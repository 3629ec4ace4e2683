"""Similarity and competence of a goal attempt (paper's SAGG-RIAC competence).

Sim(yg, y) = -min(1, D(yg, y) / D(yg, yorg)) measures how much of the way from the origin
outcome to the goal was covered: 0 is a perfect hit, -1 means no closer than where we started.
D is the Euclidean distance rescaled to [0, 1] over the outcome space [-1, 1]^m (divided by the
diagonal 2 * sqrt(m)); the ratio is scale free, the rescaling keeps D comparable across worlds.

competence = Sim if Sim <= eps_sim else 0.  eps_sim (in [-1, 0]) is a success tolerance: an
attempt closer to the goal than |eps_sim| of the goal's distance from the origin counts as a
full success (competence 0), so tiny noisy errors do not look like progress or regress.
"""

from __future__ import annotations

import numpy as np

OUTCOME_LOW = -1.0
OUTCOME_HIGH = 1.0


def diagonal(dim: int) -> float:
    """Length of the diagonal of [-1, 1]^dim (the largest possible outcome distance)."""
    return float((OUTCOME_HIGH - OUTCOME_LOW) * np.sqrt(dim))


def rescaled_distance(a: np.ndarray, b: np.ndarray) -> float:
    """D(a, b): Euclidean distance divided by the outcome space's diagonal, in [0, 1]."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return float(np.linalg.norm(a - b) / diagonal(a.shape[-1]))


def similarity(goal: np.ndarray, outcome: np.ndarray, origin: np.ndarray) -> float:
    """Sim = -min(1, D(goal, outcome) / D(goal, origin)).

    A goal equal to the origin makes the ratio undefined: we return 0 if the outcome hits it
    exactly and -1 otherwise (any miss of a zero-length task is a total miss).
    """
    d_reach = rescaled_distance(goal, outcome)
    d_start = rescaled_distance(goal, origin)
    if d_start == 0.0:
        return 0.0 if d_reach == 0.0 else -1.0
    return -min(1.0, d_reach / d_start)


def competence(goal: np.ndarray, outcome: np.ndarray, origin: np.ndarray, eps_sim: float) -> float:
    """competence = Sim if Sim <= eps_sim else 0 (exactly as stated in issue 4)."""
    sim = similarity(goal, outcome, origin)
    return sim if sim <= eps_sim else 0.0


def origin_vector(origin: tuple[float, ...] | None, outcome_dim: int) -> np.ndarray:
    """The configured origin, or the centre of the outcome space when None."""
    if origin is None:
        return np.full(outcome_dim, 0.5 * (OUTCOME_LOW + OUTCOME_HIGH))
    vec = np.asarray(origin, dtype=float)
    if vec.shape != (outcome_dim,):
        raise ValueError(f"origin has shape {vec.shape}, expected ({outcome_dim},)")
    return vec
