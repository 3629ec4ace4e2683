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

Two switches of LearnerConfig make variants of that choice, each independent of the other;
their defaults are the choice above:

- ``strategy_choice_order: region-first`` (what, then how, then who): the goal is chosen as
  SAGG-RIAC chooses it, by GoalSelector over the pooled tree in all three modes (mode 2: a goal
  uniform over the box, its leaf follows), then the strategy, and so the teacher, is the one of
  largest value / cost in that leaf, ties drawn from the rng passed in. No mode draws a
  strategy at random: a teacher is asked because it is worth its cost where the goal lies.
- ``strategy_value: gain``: a pair's value is its gain (strategy_regions.StrategyRegions.gain,
  an untried pair the largest) instead of eq. 2's interest; with order ``pair``, modes 1 and 3
  draw by gain / cost in eq. 3 exactly as they draw by interest / cost.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .config import CHOICE_ORDERS, STRATEGY_VALUES
from .goal_selection import MODES, GoalSelector
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
    """Draws a PairChoice from StrategyRegions with the three modes' probabilities, in the
    ``order`` and by the ``value`` LearnerConfig names (module docstring)."""

    def __init__(self, regions: StrategyRegions, strategies: Sequence[Strategy],
                 p_modes: tuple[float, float, float], mode3_radius: float,
                 order: str = "pair", value: str = "interest") -> None:
        names = tuple(s.name for s in strategies)
        if names != regions.strategies:
            raise ValueError(f"the regions keep {regions.strategies}, not {names}")
        p = np.asarray(p_modes, dtype=float)
        if p.shape != (3,) or np.any(p < 0) or abs(p.sum() - 1.0) > 1e-9:
            raise ValueError(f"p_modes must be 3 probabilities summing to 1, got {p_modes}")
        if order not in CHOICE_ORDERS:
            raise ValueError(f"order must be one of {', '.join(CHOICE_ORDERS)}, got {order!r}")
        if value not in STRATEGY_VALUES:
            raise ValueError(f"value must be one of {', '.join(STRATEGY_VALUES)}, got "
                             f"{value!r}")
        self.regions = regions
        self.strategies = tuple(strategies)
        self.costs = np.array([s.cost for s in strategies], dtype=float)
        self.p_modes = p
        self.mode3_radius = mode3_radius
        self.order = order
        self.value = value
        # region-first chooses its goals as SAGG-RIAC does, over the same pooled tree
        self.goal_selector = GoalSelector(regions.tree, p_modes, mode3_radius)

    def values(self) -> np.ndarray:
        """(leaves, strategies): each pair's value, its interest or its gain."""
        return self.regions.gains() if self.value == "gain" else self.regions.interests()

    def weights(self) -> np.ndarray:
        """(leaves, strategies): each pair's value divided by its strategy's cost."""
        return self.values() / self.costs[None, :]

    def best_strategy(self, leaf: Region, rng: np.random.Generator) -> Strategy:
        """The strategy of largest value / cost in ``leaf``; equal ones drawn from ``rng``
        (only then: a unique best draws nothing)."""
        if self.value == "gain":
            values = [self.regions.gain(s.name, leaf) for s in self.strategies]
        else:
            values = [self.regions.interest(s.name, leaf) for s in self.strategies]
        w = np.asarray(values, dtype=float) / self.costs
        best = np.flatnonzero(w == w.max())
        j = int(best[0]) if len(best) == 1 else int(rng.choice(best))
        return self.strategies[j]

    def probabilities(self) -> np.ndarray:
        """(leaves, strategies): mode 1's probability of each pair (order ``pair``)."""
        leaves = self.regions.leaves
        volumes = np.array([leaf.volume for leaf in leaves])
        fallback = volumes[:, None] / self.costs[None, :]
        return pair_probabilities(self.weights(), fallback).reshape(fallback.shape)

    def sample(self, rng: np.random.Generator) -> PairChoice:
        if self.order == "region-first":
            return self._sample_region_first(rng)
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

    def _sample_region_first(self, rng: np.random.Generator) -> PairChoice:
        """SAGG-RIAC's goal (GoalSelector, all modes), then the best strategy in its leaf."""
        choice = self.goal_selector.sample(rng)
        leaves = self.regions.leaves
        if choice.region_index < 0:  # mode 2: the goal was drawn over the box
            region = self.regions.tree.leaf_for(choice.goal)
            i = leaves.index(region)
        else:
            i, region = choice.region_index, leaves[choice.region_index]
        return PairChoice(self.best_strategy(region, rng), choice.goal, choice.mode, i, region)
