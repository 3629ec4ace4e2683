"""A copy of the region tree that can cross a process boundary, and goal choice from it.

The interest computer owns the tree; the goal generator only needs, for each leaf, its box,
its interest and its least competent goal. A snapshot carries exactly that (plus every inner
region, for plots), and offers the same interface as the tree to GoalSelector, so a goal drawn
from a snapshot is the very goal the tree itself would give for the same random stream.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .region_tree import Region, RegionTree


@dataclass(frozen=True)
class RegionSummary:
    """One region as the graph sees it; `goals`/`competences` hold only the least competent
    goal, which is all that goal mode 3 reads."""

    id: int
    parent_id: int
    low: np.ndarray
    high: np.ndarray
    interest: float
    goal_count: int
    is_leaf: bool
    least_competent_goal: np.ndarray | None = None

    @property
    def volume(self) -> float:
        return float(np.prod(self.high - self.low))

    @property
    def goals(self) -> list[np.ndarray]:
        return [] if self.least_competent_goal is None else [self.least_competent_goal]

    @property
    def competences(self) -> list[float]:
        return [] if self.least_competent_goal is None else [0.0]


@dataclass
class RegionSnapshot:
    """Every region, parents before children; quacks like RegionTree for GoalSelector."""

    regions: list[RegionSummary]
    goal_count: int = 0
    split_count: int = 0
    _leaves: list[RegionSummary] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.regions:
            raise ValueError("a region snapshot needs at least the root region")
        self._leaves = [r for r in self.regions if r.is_leaf]

    @property
    def root(self) -> RegionSummary:
        return self.regions[0]

    @property
    def leaves(self) -> list[RegionSummary]:
        return list(self._leaves)

    def interests(self) -> np.ndarray:
        return np.array([leaf.interest for leaf in self._leaves])


class RegionIds:
    """Stable ids for the regions of one tree: a region keeps its id for the whole run."""

    def __init__(self) -> None:
        self._ids: dict[int, int] = {}
        self._keep: list[Region] = []  # holds the regions so that their id() stays unique

    def __call__(self, region: Region) -> int:
        key = id(region)
        if key not in self._ids:
            self._ids[key] = len(self._ids)
            self._keep.append(region)
        return self._ids[key]


def map_order(tree: RegionTree) -> list[tuple[Region, Region | None]]:
    """(region, parent) for every region in the order of a map: inner regions breadth-first
    (root first), then the leaves in tree.leaves order, which is the order GoalSelector
    indexes them by; every parent comes before its children. Region ids are handed out in
    this order, so that every process that folds the same goals names the regions alike."""
    order: list[tuple[Region, Region | None]] = []
    queue: list[tuple[Region, Region | None]] = [(tree.root, None)]
    while queue:
        region, parent = queue.pop(0)
        if region.children is None:
            continue
        order.append((region, parent))
        queue.extend((child, region) for child in region.children)
    parents = {id(child): region for region, _ in order for child in region.children}
    order.extend((leaf, parents.get(id(leaf))) for leaf in tree.leaves)
    return order


def snapshot(tree: RegionTree, ids: RegionIds, goal_count: int,
             interests: Mapping[int, float] | None = None) -> RegionSnapshot:
    """Every region in map_order. `interests` (by id() of each leaf) spares recomputing the
    leaves' interests when the caller keeps them (live_regions.py)."""
    counts: dict[int, int] = {}
    _count_goals(tree.root, counts)
    regions = [_summary(region, ids, -1 if parent is None else ids(parent), tree, counts,
                        interests) for region, parent in map_order(tree)]
    inner = sum(1 for r in regions if not r.is_leaf)
    return RegionSnapshot(regions, goal_count, inner)


def _summary(region: Region, ids: RegionIds, parent: int, tree: RegionTree,
             counts: dict[int, int], interests: Mapping[int, float] | None) -> RegionSummary:
    least = None
    if region.goals:
        least = np.array(region.goals[int(np.argmin(region.competences))], dtype=float)
    interest = 0.0
    if region.is_leaf:
        interest = (interests[id(region)] if interests is not None
                    else region.interest(tree.zeta, tree.noise_correction))
    return RegionSummary(ids(region), parent, region.low.copy(), region.high.copy(), interest,
                         counts[id(region)], region.is_leaf, least)


def _count_goals(region: Region, counts: dict[int, int]) -> int:
    """Goals held under each region (by id()), in one pass over the tree: a snapshot is
    taken at every attempted goal."""
    if region.children is None:
        n = len(region.goals)
    else:
        n = sum(_count_goals(child, counts) for child in region.children)
    counts[id(region)] = n
    return n
