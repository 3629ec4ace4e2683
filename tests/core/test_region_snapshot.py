"""A snapshot of the tree gives GoalSelector exactly what the tree gives it."""

import numpy as np

from sgim_nodes.core.goal_selection import GoalSelector
from sgim_nodes.core.region_snapshot import RegionIds, RegionSnapshot, RegionSummary, snapshot
from sgim_nodes.core.region_tree import RegionTree


def _grown_tree(seed: int = 0, n: int = 400) -> RegionTree:
    rng = np.random.default_rng(seed)
    tree = RegionTree(np.full(2, -1.0), np.full(2, 1.0), max_goals=30, zeta=10)
    for k in range(n):
        goal = rng.uniform(-1, 1, 2)
        # competence improves over time in the right half only: splits follow x = 0
        comp = -1.0 + (k / n if goal[0] > 0 else 0.0) + 0.05 * rng.standard_normal()
        tree.add(goal, min(0.0, comp))
    return tree


def test_goals_drawn_from_a_snapshot_equal_goals_drawn_from_the_tree():
    tree = _grown_tree()
    snap = snapshot(tree, RegionIds(), goal_count=400)
    assert len(snap.leaves) == len(tree.leaves) > 2
    p = (0.5, 0.2, 0.3)
    from_tree, from_snap = GoalSelector(tree, p, 0.05), GoalSelector(snap, p, 0.05)
    rng_a, rng_b = np.random.default_rng(5), np.random.default_rng(5)
    for _ in range(300):
        a, b = from_tree.sample(rng_a), from_snap.sample(rng_b)
        assert a.mode == b.mode and a.region_index == b.region_index
        assert np.array_equal(a.goal, b.goal)


def test_snapshot_structure_ids_and_counts():
    tree = _grown_tree(n=200)
    ids = RegionIds()
    snap = snapshot(tree, ids, goal_count=200)
    assert snap.root.parent_id == -1 and snap.root.id == 0
    seen = set()
    for region in snap.regions:
        assert region.parent_id == -1 or region.parent_id in seen  # parents first
        seen.add(region.id)
    assert len(seen) == len(snap.regions)
    assert snap.root.goal_count == 200 == sum(leaf.goal_count for leaf in snap.leaves)
    assert snap.split_count == len(snap.regions) - len(snap.leaves)
    np.testing.assert_array_equal(snap.interests(), tree.interests())
    # Ids are stable: more goals and splits later keep every old region's id.
    before = {(tuple(r.low), tuple(r.high)): r.id for r in snap.regions}
    rng = np.random.default_rng(9)
    for _ in range(200):
        tree.add(rng.uniform(-1, 1, 2), -0.5)
    after = {(tuple(r.low), tuple(r.high)): r.id for r in snapshot(tree, ids, 400).regions}
    for box, rid in before.items():
        assert after[box] == rid


def test_least_competent_goal_is_the_leafs_worst():
    tree = RegionTree(np.full(2, -1.0), np.full(2, 1.0), max_goals=50, zeta=10)
    tree.add(np.array([0.1, 0.1]), -0.2)
    tree.add(np.array([0.5, -0.3]), -0.9)
    tree.add(np.array([-0.4, 0.2]), -0.4)
    (leaf,) = snapshot(tree, RegionIds(), 3).leaves
    np.testing.assert_array_equal(leaf.least_competent_goal, [0.5, -0.3])


def test_an_empty_snapshot_is_refused():
    import pytest

    with pytest.raises(ValueError):
        RegionSnapshot([])
    assert RegionSummary(0, -1, np.zeros(2), np.ones(2), 0.0, 0, True).goals == []
