"""SGIM-ACTS's choice of a (strategy, region) pair and of a goal in it, in three modes.

The paper keeps SAGG-RIAC's three modes and lets them choose the strategy with the region:

- mode 1 (``p_mode1``): a pair drawn with probability proportional to its interest divided by
  its strategy's cost (minus the smallest such value, as eq. 3 does for regions), then a goal
  uniform in the region: learn where, and how, progress is cheapest;
- mode 2 (``p_mode2``): a strategy drawn uniformly and a goal uniform in the whole outcome
  box, so that no strategy and no region is ever given up for good (a strategy's interest can
  only be measured by using it);
- mode 3 (``p_mode3``): a pair drawn as in mode 1, then a goal near the least competent goal
  that strategy attempted in that region: the frontier of that strategy's progress there.

LearnerConfig's p_mode1/2/3 (SGIM-lineage code: 0.6, 0.2, 0.2) and mode3_radius_noise are
reused: they say how much to exploit the measured interest and how much to keep measuring,
which is the same trade-off whether the arms are regions or (strategy, region) pairs.

When every pair has the same weight (at the start, or where nothing progresses), mode 1 draws
a pair with probability proportional to its region's volume divided by its strategy's cost:
uniform over the space as GoalSelector falls back to, and the cheap strategies first, since
nothing says the dear ones are worth their cost.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .goal_selection import MODES
from .region_tree import Region
from .strategies import Strategy
from .strategy_regions import StrategyRegions


@dataclass(frozen=True)
class PairChoice:
    """One episode's choice: the strategy, the goal, the mode, the leaf holding the goal
    (its index in the tree's leaves at the time of the choice, and its box)."""

    strategy: Strategy
    goal: np.ndarray
    mode: int
    region_index: int
    region: Region


def pair_probabilities(weights: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Eq. 3 over pairs: P proportional to weight - min(weight); when every weight is equal,
    proportional to ``fallback`` (both arrays of one shape, flattened)."""
    w = np.asarray(weights, dtype=float).ravel()
    w = w - w.min()
    if w.sum() > 0.0:
        return w / w.sum()
    f = np.asarray(fallback, dtype=float).ravel()
    return f / f.sum()


class StrategyChooser:
    """Draws a PairChoice from StrategyRegions with the three modes' probabilities."""

    def __init__(self, regions: StrategyRegions, strategies: Sequence[Strategy],
                 p_modes: tuple[float, float, float], mode3_radius: float) -> None:
        names = tuple(s.name for s in strategies)
        if names != regions.strategies:
            raise ValueError(f"the regions keep {regions.strategies}, not {names}")
        p = np.asarray(p_modes, dtype=float)
        if p.shape != (3,) or np.any(p < 0) or abs(p.sum() - 1.0) > 1e-9:
            raise ValueError(f"p_modes must be 3 probabilities summing to 1, got {p_modes}")
        self.regions = regions
        self.strategies = tuple(strategies)
        self.costs = np.array([s.cost for s in strategies], dtype=float)
        self.p_modes = p
        self.mode3_radius = mode3_radius

    def weights(self) -> np.ndarray:
        """(leaves, strategies): each pair's interest divided by its strategy's cost."""
        return self.regions.interests() / self.costs[None, :]

    def probabilities(self) -> np.ndarray:
        """(leaves, strategies): mode 1's probability of each pair."""
        leaves = self.regions.leaves
        volumes = np.array([leaf.volume for leaf in leaves])
        fallback = volumes[:, None] / self.costs[None, :]
        return pair_probabilities(self.weights(), fallback).reshape(fallback.shape)

    def sample(self, rng: np.random.Generator) -> PairChoice:
        mode = int(rng.choice(MODES, p=self.p_modes))
        leaves = self.regions.leaves
        root = self.regions.tree.root
        if mode == 2:
            strategy = self.strategies[int(rng.integers(len(self.strategies)))]
            goal = rng.uniform(root.low, root.high)
            leaf = self.regions.tree.leaf_for(goal)
            return PairChoice(strategy, goal, 2, leaves.index(leaf), leaf)
        probs = self.probabilities().ravel()
        k = int(rng.choice(len(probs), p=probs))
        i, j = divmod(k, len(self.strategies))
        region, strategy = leaves[i], self.strategies[j]
        history = self.regions.history(strategy.name, region)
        if mode == 1 or not history.goals:
            # mode 3 without a goal of that strategy there has no frontier: uniform in it.
            return PairChoice(strategy, rng.uniform(region.low, region.high), mode, i, region)
        worst = history.goals[int(np.argmin(history.competences))]
        r = self.mode3_radius
        goal = np.clip(worst + rng.uniform(-r, r, size=worst.shape), region.low, region.high)
        return PairChoice(strategy, goal, 3, i, region)
