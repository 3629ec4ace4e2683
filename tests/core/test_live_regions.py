"""LiveRegions gives GoalSelector exactly what its tree gives, and names regions as a map
snapshot taken after every goal does (the interest computer's map and the goal generator's
Goal.region_id must agree)."""

import numpy as np

from sgim_nodes.core.goal_selection import GoalSelector
from sgim_nodes.core.live_regions import LiveRegions
from sgim_nodes.core.region_snapshot import RegionIds, snapshot
from sgim_nodes.core.region_tree import RegionTree


def _tree() -> RegionTree:
    return RegionTree(np.full(2, -1.0), np.full(2, 1.0), max_goals=30, zeta=10,
                      noise_correction=0.5, split="balanced")


def _attempt(rng: np.random.Generator, k: int, n: int) -> tuple[np.ndarray, float]:
    goal = rng.uniform(-1, 1, 2)
    # competence improves over time in the right half only: splits follow x = 0
    comp = -1.0 + (k / n if goal[0] > 0 else 0.0) + 0.05 * rng.standard_normal()
    return goal, min(0.0, comp)


def test_goals_drawn_while_folding_equal_the_trees_goals():
    live, tree = LiveRegions(_tree()), _tree()
    p = (0.5, 0.2, 0.3)
    from_live, from_tree = GoalSelector(live, p, 0.05), GoalSelector(tree, p, 0.05)
    rng_a, rng_b, attempts = np.random.default_rng(5), np.random.default_rng(5), \
        np.random.default_rng(0)
    for k in range(600):
        a, b = from_live.sample(rng_a), from_tree.sample(rng_b)
        assert a.mode == b.mode and a.region_index == b.region_index
        assert np.array_equal(a.goal, b.goal)
        goal, comp = _attempt(attempts, k, 600)
        live.add(goal, comp)
        tree.add(goal, comp)
        np.testing.assert_array_equal(live.interests(), tree.interests())
    assert len(tree.leaves) > 8 and live.goal_count == 600


def test_ids_equal_those_of_a_snapshot_after_every_goal():
    """The goal generator never takes a snapshot: its ids must still be the map's."""
    live, tree, ids = LiveRegions(_tree()), _tree(), RegionIds()
    attempts = np.random.default_rng(3)
    for k in range(500):
        goal, comp = _attempt(attempts, k, 500)
        live.add(goal, comp)
        tree.add(goal, comp)
        expected = snapshot(tree, ids, k + 1)  # what the interest computer publishes
    corners = [corner for r in expected.leaves for corner in (r.low, r.high)]  # on borders
    for point in [*np.random.default_rng(4).uniform(-1, 1, (50, 2)), *corners]:
        leaf = next(r for r in expected.leaves
                    if np.all(point >= r.low) and np.all(point <= r.high))
        assert live.region_id(point) == leaf.id
    assert live.region_id(np.array([2.0, 0.0])) == -1
    got = live.snapshot()
    assert [(r.id, r.parent_id) for r in got.regions] == \
        [(r.id, r.parent_id) for r in expected.regions]
    assert [r.interest for r in got.regions] == [r.interest for r in expected.regions]
    assert got.goal_count == 500 and got.split_count == expected.split_count > 8


def test_a_resumed_tree_is_named_as_its_first_snapshot_names_it():
    tree = _tree()
    attempts = np.random.default_rng(8)
    for k in range(300):
        tree.add(*_attempt(attempts, k, 300))
    live = LiveRegions(tree, goal_count=300)
    expected = snapshot(tree, RegionIds(), 300)
    assert [r.id for r in live.snapshot().regions] == [r.id for r in expected.regions]
    np.testing.assert_array_equal(live.interests(), tree.interests())
