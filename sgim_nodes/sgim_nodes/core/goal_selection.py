"""Goal selection by the three SAGG-RIAC modes.

Mode 1 explores where competence changes fastest (region by interest, eq. 3, uniform goal in
it); mode 2 keeps sampling the whole space so no region is forgotten; mode 3 revisits the
neighbourhood of a region's worst attempted goal, where progress is most likely to be found.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .region_tree import Region, RegionTree

MODES = (1, 2, 3)


def region_probabilities(interests: np.ndarray, volumes: np.ndarray | None = None) -> np.ndarray:
    """Eq. 3: P(region) proportional to interest - min(interest).

    When every interest is equal (all weights 0, e.g. at the start) we fall back to
    probabilities proportional to volume (uniform over the space) if volumes are given, else
    uniform over regions: eq. 3 is undefined there, and volume weighting avoids favouring the
    many small regions a deep tree has.
    """
    interests = np.asarray(interests, dtype=float)
    weights = interests - interests.min()
    total = weights.sum()
    if total > 0.0:
        return weights / total
    if volumes is not None:
        v = np.asarray(volumes, dtype=float)
        if v.sum() > 0:
            return v / v.sum()
    return np.full(len(interests), 1.0 / len(interests))


@dataclass(frozen=True)
class GoalChoice:
    goal: np.ndarray
    mode: int
    region_index: int  # index in tree.leaves, -1 for mode 2


class GoalSelector:
    """Draws goals from a RegionTree with configurable mode probabilities."""

    def __init__(self, tree: RegionTree, p_modes: tuple[float, float, float],
                 mode3_radius: float) -> None:
        p = np.asarray(p_modes, dtype=float)
        if p.shape != (3,) or np.any(p < 0) or abs(p.sum() - 1.0) > 1e-9:
            raise ValueError(f"p_modes must be 3 probabilities summing to 1, got {p_modes}")
        self.tree = tree
        self.p_modes = p
        self.mode3_radius = mode3_radius

    def choose_region(self, rng: np.random.Generator) -> tuple[int, Region]:
        leaves = self.tree.leaves
        probs = region_probabilities(self.tree.interests(), np.array([r.volume for r in leaves]))
        i = int(rng.choice(len(leaves), p=probs))
        return i, leaves[i]

    def sample(self, rng: np.random.Generator) -> GoalChoice:
        mode = int(rng.choice(MODES, p=self.p_modes))
        root = self.tree.root
        if mode == 2:
            return GoalChoice(rng.uniform(root.low, root.high), 2, -1)
        i, region = self.choose_region(rng)
        if mode == 1 or not region.goals:
            # mode 3 in a region without goals has no "least competent goal": uniform in it.
            return GoalChoice(rng.uniform(region.low, region.high), mode, i)
        worst = region.goals[int(np.argmin(region.competences))]
        r = self.mode3_radius
        goal = np.clip(worst + rng.uniform(-r, r, size=worst.shape), region.low, region.high)
        return GoalChoice(goal, 3, i)
