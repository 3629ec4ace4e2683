"""The paper's local inverse model: from a goal outcome to an action.

Among the l_max stored outcomes nearest to the goal, the most reliable one is the one that is
close to the goal AND whose neighbourhood is consistent (its k_max neighbours were produced by
similar actions): averaging actions from a redundant, inconsistent neighbourhood would give an
action that reaches none of them.  reliability = distance + alpha * variance (lower is better);
the chosen candidate's neighbours' actions are then interpolated with normalised Gaussian
weights of their outcome's distance to the goal.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .memory import Memory


def action_variance(actions: np.ndarray) -> float:
    """Mean per-dimension variance of a set of actions (mean squared distance to their mean,
    divided by the action dimension) so that the scale does not grow with the dimension."""
    actions = np.asarray(actions, dtype=float)
    centred = actions - actions.mean(axis=0)
    return float((centred**2).sum(axis=1).mean() / actions.shape[1])


def reliability(distance: float, variance: float, alpha: float) -> float:
    """Paper: distance + alpha * variance (lower = more reliable)."""
    return float(distance + alpha * variance)


def gaussian_weights(distances: np.ndarray, sigma: float) -> np.ndarray:
    """Normalised exp(-d^2 / (2 sigma^2)); computed relative to the smallest distance so that
    far-away neighbours do not all underflow to zero."""
    d2 = np.asarray(distances, dtype=float) ** 2
    w = np.exp(-(d2 - d2.min()) / (2.0 * sigma**2))
    return w / w.sum()


@dataclass(frozen=True)
class InverseEstimate:
    action: np.ndarray
    neighbour_indices: np.ndarray  # memory indices of the interpolated neighbours
    weights: np.ndarray
    candidate_index: int  # memory index of the most reliable candidate
    reliability: float


class InverseModel:
    """Reads the memory only; never learns on its own."""

    def __init__(self, memory: Memory, l_max: int, k_max: int, alpha: float,
                 sigma: float) -> None:
        self.memory = memory
        self.l_max = l_max
        self.k_max = k_max
        self.alpha = alpha
        self.sigma = sigma

    def estimate(self, goal: np.ndarray) -> InverseEstimate | None:
        """None when the memory is empty."""
        mem = self.memory
        if len(mem) == 0:
            return None
        goal = np.asarray(goal, dtype=float)
        cand_d, cand_i = mem.nearest(goal, self.l_max)
        _, neigh_i = mem.nearest(mem.outcomes[cand_i], self.k_max)
        scores = np.array([
            reliability(cand_d[j], action_variance(mem.actions[neigh_i[j]]), self.alpha)
            for j in range(len(cand_i))
        ])
        best = int(np.argmin(scores))
        idx = neigh_i[best]
        dist_to_goal = np.linalg.norm(mem.outcomes[idx] - goal, axis=1)
        w = gaussian_weights(dist_to_goal, self.sigma)
        action = np.clip(w @ mem.actions[idx], -1.0, 1.0)
        return InverseEstimate(action, idx, w, int(cand_i[best]), float(scores[best]))

    def __call__(self, goal: np.ndarray) -> np.ndarray | None:
        est = self.estimate(goal)
        return None if est is None else est.action
