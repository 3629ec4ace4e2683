"""A region tree that keeps what goal choice reads up to date as goals are folded in.

GoalSelector reads every leaf's interest at every goal; RegionTree recomputes them all (one
numpy window per leaf: about 3 ms at 112 leaves), although one attempted goal changes the
interest of one leaf only, or of the two it splits into. LiveRegions folds each goal into its
tree and recomputes just those, and names the regions with stable ids in map order as they
appear, so that every process folding the same goals in the same order gives the same ids. The
values are the tree's own, computed by the same calls: a goal drawn from LiveRegions is the
very goal the tree gives for the same random stream (tests/core/test_live_regions.py).

The graph's goal generator draws its goals from one, the interest computer publishes the map
of another: the goal no longer waits for a whole map to cross two processes.
"""

from __future__ import annotations

import numpy as np

from .region_snapshot import RegionIds, RegionSnapshot, map_order, snapshot
from .region_tree import Region, RegionTree


class LiveRegions:
    """A RegionTree with cached leaf interests and stable region ids; quacks like RegionTree
    for GoalSelector."""

    def __init__(self, tree: RegionTree, goal_count: int = 0) -> None:
        self.tree = tree
        self.goal_count = goal_count  # attempted goals folded in (those of a resumed tree too)
        self.ids = RegionIds()
        self._interests: dict[int, float] = {}  # by id() of each leaf
        for leaf in tree.leaves:
            self._measure(leaf)
        self._name_regions()

    @property
    def root(self) -> Region:
        return self.tree.root

    @property
    def leaves(self) -> list[Region]:
        return self.tree.leaves

    def interests(self) -> np.ndarray:
        return np.array([self._interests[id(leaf)] for leaf in self.tree.leaves])

    def add(self, goal: np.ndarray, competence: float) -> None:
        """Fold one attempted goal in (RegionTree.add), then refresh what it changed."""
        leaf = self.tree.add(goal, competence)
        self.goal_count += 1
        if leaf.children is None:
            self._measure(leaf)
            return
        del self._interests[id(leaf)]  # split: an inner region now, its children are leaves
        for child in leaf.children:
            self._measure(child)
        self._name_regions()

    def region_id(self, point: np.ndarray) -> int:
        """The id of the first leaf (tree.leaves order) whose closed box holds `point`; -1 if
        none does (a point outside the space)."""
        inside = np.all((point >= self._lows) & (point <= self._highs), axis=1)
        return int(self._leaf_ids[np.argmax(inside)]) if inside.any() else -1

    def snapshot(self) -> RegionSnapshot:
        return snapshot(self.tree, self.ids, self.goal_count, self._interests)

    def _measure(self, leaf: Region) -> None:
        self._interests[id(leaf)] = leaf.interest(self.tree.zeta, self.tree.noise_correction)

    def _name_regions(self) -> None:
        """Ids for new regions, in map order; and the leaves' boxes, for region_id."""
        for region, _ in map_order(self.tree):
            self.ids(region)
        leaves = self.tree.leaves
        self._lows = np.array([leaf.low for leaf in leaves])
        self._highs = np.array([leaf.high for leaf in leaves])
        self._leaf_ids = np.array([self.ids(leaf) for leaf in leaves])
