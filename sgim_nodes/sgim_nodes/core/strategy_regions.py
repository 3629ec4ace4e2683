"""Competence per (strategy, region): the region tree of SGIM-ACTS.

SGIM-ACTS measures the interest of each pair (strategy, region): how fast the learner's
competence at the region's goals changes when it uses that strategy there. Design:

- ``StrategyRegions`` wraps an unchanged ``RegionTree`` (region_tree.py). The tree receives
  every attempted goal, whatever strategy attempted it, and splits on those pooled goals:
  one partition of the outcome space for all strategies, so that their interests compare
  region by region and a region is not cut finer for one strategy than for another; the
  other learners' tree is untouched.
- Next to it, each leaf holds one chronological history (goals, competences) per strategy.
  When the tree splits a leaf, each of that leaf's histories is divided between the two
  children by the same cut, keeping its order, as the tree divides its own goals.
- The interest of a pair is eq. 2 (region_tree.interest) on that pair's history alone, with
  the tree's zeta and noise correction; dividing it by the strategy's cost is the choice's
  business (strategy_choice.py), so the plain progress stays readable here.
- The gain of a pair (LearnerConfig.strategy_value ``gain``) is the mean of 1 + competence
  over the last zeta episodes of its history: how near its goals the strategy brought the
  learner there, not how fast that changed. A pair without history has UNTRIED_GAIN.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .region_tree import Region, RegionTree, interest

UNTRIED_GAIN = 1.0
"""The gain of a pair never tried in its region: the largest a gain can be (competence 0, a
full success), so that a strategy is tried at least once where the tried ones gain little
instead of being judged on no evidence."""


@dataclass
class History:
    """One strategy's attempted goals and their competences in one region, oldest first."""

    goals: list[np.ndarray] = field(default_factory=list)
    competences: list[float] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.goals)


class StrategyRegions:
    """A RegionTree whose leaves also keep one competence history per strategy."""

    def __init__(self, tree: RegionTree, strategies: Sequence[str]) -> None:
        if not strategies:
            raise ValueError("StrategyRegions needs at least one strategy")
        if len(set(strategies)) != len(strategies):
            raise ValueError(f"strategy names must be distinct, got {list(strategies)}")
        if any(len(leaf.goals) for leaf in tree.leaves):
            raise ValueError("StrategyRegions needs an empty tree: its goals have no strategy")
        self.tree = tree
        self.strategies = tuple(strategies)
        self._histories: dict[Region, dict[str, History]] = {tree.root: self._empty()}

    def _empty(self) -> dict[str, History]:
        return {name: History() for name in self.strategies}

    @property
    def leaves(self) -> list[Region]:
        return self.tree.leaves

    def history(self, strategy: str, region: Region) -> History:
        if strategy not in self.strategies:
            raise ValueError(f"unknown strategy {strategy!r}; known: {self.strategies}")
        if region not in self._histories:
            raise ValueError("not a leaf of this tree")
        return self._histories[region][strategy]

    def add(self, strategy: str, goal: np.ndarray, competence: float) -> Region:
        """Record one goal attempted with ``strategy``; returns the leaf that holds it now
        (after a split, the child it went to)."""
        if strategy not in self.strategies:
            raise ValueError(f"unknown strategy {strategy!r}; known: {self.strategies}")
        goal = np.clip(np.asarray(goal, dtype=float), self.tree.root.low, self.tree.root.high)
        leaf = self.tree.leaf_for(goal)
        histories = self._histories[leaf]
        histories[strategy].goals.append(goal)
        histories[strategy].competences.append(float(competence))
        self.tree.add(goal, competence)
        if leaf.children is not None:  # the tree split the leaf on this goal
            self._divide(leaf)
            return self.tree.leaf_for(goal)
        return leaf

    def _divide(self, parent: Region) -> None:
        left, right = parent.children
        old = self._histories.pop(parent)
        self._histories[left], self._histories[right] = self._empty(), self._empty()
        for name, history in old.items():
            for goal, comp in zip(history.goals, history.competences, strict=True):
                side = left if goal[parent.split_dim] < parent.split_value else right
                self._histories[side][name].goals.append(goal)
                self._histories[side][name].competences.append(comp)

    def interest(self, strategy: str, region: Region) -> float:
        """Eq. 2 on the pair's own history (not divided by the cost)."""
        return interest(self.history(strategy, region).competences, self.tree.zeta,
                        self.tree.noise_correction)

    def interests(self) -> np.ndarray:
        """(leaves, strategies): each pair's interest, leaves in tree order."""
        return np.array([[self.interest(s, leaf) for s in self.strategies]
                         for leaf in self.tree.leaves]).reshape(len(self.tree.leaves),
                                                                len(self.strategies))

    def gain(self, strategy: str, region: Region) -> float:
        """The mean of 1 + competence over the pair's last zeta episodes (competences lie in
        [-1, 0], so gains in [0, 1]); UNTRIED_GAIN when the pair has none."""
        competences = self.history(strategy, region).competences
        if not competences:
            return UNTRIED_GAIN
        window = np.asarray(competences[-self.tree.zeta:], dtype=float)
        return float(np.mean(1.0 + window))

    def gains(self) -> np.ndarray:
        """(leaves, strategies): each pair's gain, leaves in tree order."""
        return np.array([[self.gain(s, leaf) for s in self.strategies]
                         for leaf in self.tree.leaves]).reshape(len(self.tree.leaves),
                                                                len(self.strategies))

    def counts(self) -> np.ndarray:
        """(leaves, strategies): how many goals each pair has attempted."""
        return np.array([[len(self._histories[leaf][s]) for s in self.strategies]
                         for leaf in self.tree.leaves], dtype=int)
