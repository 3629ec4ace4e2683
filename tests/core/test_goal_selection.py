"""Region probabilities (eq. 3) by hand, and sampling frequencies with fixed seeds."""

import numpy as np
import pytest

from sgim_nodes.core.goal_selection import GoalSelector, region_probabilities
from sgim_nodes.core.region_tree import RegionTree


def test_region_probabilities_eq3_hand_values():
    # weights = interest - min = [0, 0.2, 0.5] -> / 0.7
    assert region_probabilities([0.1, 0.3, 0.6]) == pytest.approx([0.0, 2 / 7, 5 / 7])


def test_region_probabilities_all_equal():
    assert region_probabilities([0.2, 0.2], volumes=[1.0, 3.0]) == pytest.approx([0.25, 0.75])
    assert region_probabilities([0.0, 0.0, 0.0, 0.0]) == pytest.approx([0.25] * 4)


def _two_region_tree():
    """Left leaf (x < 0) interest 0.4, right leaf 0, then a third value via a third region."""
    tree = RegionTree(np.array([-1.0, -1.0]), np.array([1.0, 1.0]), max_goals=8, zeta=4,
                      min_per_child=2, min_width=0.0)
    goals = [[-0.8, 0.1], [0.2, 0.3], [-0.6, -0.5], [0.4, -0.4], [-0.4, 0.6], [0.6, 0.7],
             [-0.2, -0.2], [0.8, -0.7], [0.9, 0.9]]
    comps = [-1, -0.5, -1, -0.5, -0.2, -0.5, -0.2, -0.5, -0.5]
    for g, c in zip(goals, comps, strict=True):
        tree.add(np.array(g), c)
    assert len(tree.leaves) == 2
    return tree


def test_mode_frequencies():
    tree = _two_region_tree()
    sel = GoalSelector(tree, (0.5, 0.3, 0.2), mode3_radius=0.05)
    rng = np.random.default_rng(1)
    modes = np.array([sel.sample(rng).mode for _ in range(20000)])
    freq = [np.mean(modes == m) for m in (1, 2, 3)]
    # binomial std <= 0.0036 at n = 20000; tolerance ~4 sigma
    assert freq == pytest.approx([0.5, 0.3, 0.2], abs=0.015)


def test_mode1_regions_follow_eq3_and_goals_lie_inside():
    tree = _two_region_tree()
    # interests [0.4, 0] -> all the mass on the left leaf
    sel = GoalSelector(tree, (1.0, 0.0, 0.0), mode3_radius=0.05)
    rng = np.random.default_rng(2)
    choices = [sel.sample(rng) for _ in range(500)]
    assert all(c.region_index == 0 for c in choices)
    assert all(-1 <= c.goal[0] < 0 for c in choices)
    # make the right leaf the interesting one: eq. 3 flips
    right = tree.leaves[1]
    right.competences += [-1.0, -1.0, 0.0, 0.0]  # interest |(-2) - 0| / 4 = 0.5
    left = tree.leaves[0]
    assert left.interest(4) == pytest.approx(0.4) and right.interest(4) == pytest.approx(0.5)
    choices = [sel.sample(rng) for _ in range(500)]
    assert all(c.region_index == 1 and c.goal[0] >= 0 for c in choices)


def test_mode1_with_three_regions_matches_eq3_frequencies():
    tree = _two_region_tree()
    right = tree.leaves[1]
    right.competences += [-1.0, -1.0, -0.8, -0.8]  # interest 0.4 / 4 = 0.1
    tree._leaves.append(type(right)(np.array([2.0, 2.0]), np.array([3.0, 3.0]),
                                    competences=[-0.5] * 4))  # interest 0
    # interests [0.4, 0.1, 0] -> probabilities [0.8, 0.2, 0]
    assert region_probabilities(tree.interests()) == pytest.approx([0.8, 0.2, 0.0])
    sel = GoalSelector(tree, (1.0, 0.0, 0.0), mode3_radius=0.05)
    rng = np.random.default_rng(3)
    idx = np.array([sel.sample(rng).region_index for _ in range(10000)])
    assert np.mean(idx == 0) == pytest.approx(0.8, abs=0.02)
    assert np.mean(idx == 2) == 0.0


def test_mode3_goal_near_least_competent_goal():
    tree = _two_region_tree()
    sel = GoalSelector(tree, (0.0, 0.0, 1.0), mode3_radius=0.05)
    rng = np.random.default_rng(4)
    left = tree.leaves[0]
    worst = left.goals[int(np.argmin(left.competences))]  # (-0.8, 0.1), competence -1
    assert worst == pytest.approx([-0.8, 0.1])
    for _ in range(300):
        c = sel.sample(rng)
        assert c.mode == 3 and c.region_index == 0
        assert np.all(np.abs(c.goal - worst) <= 0.05 + 1e-12)


def test_mode2_uniform_over_space():
    tree = _two_region_tree()
    sel = GoalSelector(tree, (0.0, 1.0, 0.0), mode3_radius=0.05)
    rng = np.random.default_rng(5)
    goals = np.array([sel.sample(rng).goal for _ in range(4000)])
    assert goals.min() >= -1 and goals.max() <= 1
    assert np.mean(goals[:, 0] < 0) == pytest.approx(0.5, abs=0.03)
    assert goals.mean(axis=0) == pytest.approx([0.0, 0.0], abs=0.04)


def test_invalid_mode_probabilities():
    tree = _two_region_tree()
    with pytest.raises(ValueError):
        GoalSelector(tree, (0.5, 0.5, 0.5), 0.05)
