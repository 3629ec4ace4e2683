"""Interest (eq. 2) and the split choice against hand-computed values."""

import numpy as np
import pytest

from sgim_nodes.core.region_tree import RegionTree, best_split, interest


def test_interest_hand_values():
    # older half sum -2, newer half sum -1 -> |(-2) - (-1)| / 4
    assert interest([-1, -1, -0.5, -0.5], 4) == pytest.approx(0.25)
    # only the last zeta = 4 count
    assert interest([0, 0, -1, -1, -0.5, -0.5], 4) == pytest.approx(0.25)
    # regression counts as much as progress (absolute value)
    assert interest([-0.5, -0.5, -1, -1], 4) == pytest.approx(0.25)
    # 3 values, zeta 4: the newest even count (2) is used, still divided by zeta
    assert interest([-1, -0.5, -0.2], 4) == pytest.approx(0.3 / 4)
    assert interest([-0.7] * 10, 4) == 0.0
    assert interest([], 4) == 0.0
    assert interest([-1.0], 4) == 0.0


def test_noise_correction_removes_scatter_but_keeps_a_clear_trend():
    scatter = [-1.0, 0.0, -1.0, 0.0, -1.0, 0.0, -0.5, -0.5, -1.0, 0.0, -0.5, -0.5]
    # halves of 6: means -0.5 and -0.5+... the paper's formula sees their raw difference
    raw = interest(scatter, 12)
    assert interest(scatter, 12, noise_correction=1.0) < raw or raw == 0.0
    trend = [-1.0, -1.0, -0.95, -1.0, -0.95, -1.0, 0.0, -0.05, 0.0, 0.0, -0.05, 0.0]
    # hand value: gap 0.975 - 0.017 = 0.9583, se = sqrt((var_o + var_n) / 6) with ddof 1
    older, newer = np.array(trend[:6]), np.array(trend[6:])
    se = np.sqrt((older.var(ddof=1) + newer.var(ddof=1)) / 6)
    gap = abs(older.mean() - newer.mean())
    assert interest(trend, 12, 1.0) == pytest.approx(6 * (gap - se) / 12)
    assert interest(trend, 12, 1.0) > 0.4
    assert interest([-0.3] * 12, 12, 2.0) == 0.0


# Left half (x < 0) progresses (-1, -1, -0.2, -0.2: interest 0.4 with zeta 4), right half is
# constant (interest 0); chronological order interleaves them.
GOALS = np.array([[-0.8, 0.1], [0.2, 0.3], [-0.6, -0.5], [0.4, -0.4],
                  [-0.4, 0.6], [0.6, 0.7], [-0.2, -0.2], [0.8, -0.7]])
COMPS = np.array([-1, -0.5, -1, -0.5, -0.2, -0.5, -0.2, -0.5])


def test_best_split_separates_progress_from_stagnation():
    choice = best_split(GOALS, COMPS, np.array([-1.0, -1.0]), np.array([1.0, 1.0]),
                        zeta=4, min_per_child=2, min_width=0.0)
    assert choice is not None
    assert choice.dim == 0
    assert choice.value == pytest.approx(0.0)  # midpoint of -0.2 and 0.2
    assert choice.score == pytest.approx(0.4)
    assert (choice.n_left, choice.n_right) == (4, 4)


def test_best_split_ties_go_to_the_most_balanced_cut():
    goals = np.column_stack([np.linspace(-0.9, 0.9, 10), np.zeros(10)])
    choice = best_split(goals, np.full(10, -0.5), np.array([-1.0, -1.0]),
                        np.array([1.0, 1.0]), zeta=4, min_per_child=2, min_width=0.0)
    assert choice is not None and choice.dim == 0 and choice.score == 0.0
    assert (choice.n_left, choice.n_right) == (5, 5)


def test_best_split_none_when_all_goals_coincide():
    goals = np.zeros((10, 2))
    assert best_split(goals, np.zeros(10), np.array([-1.0, -1.0]), np.array([1.0, 1.0]),
                      4, 2, 0.0) is None


def test_tree_splits_only_when_over_the_maximum():
    tree = RegionTree(np.array([-1.0, -1.0]), np.array([1.0, 1.0]), max_goals=8, zeta=4,
                      min_per_child=2, min_width=0.0)
    for g, c in zip(GOALS, COMPS, strict=True):
        tree.add(g, c)
    assert len(tree.leaves) == 1  # 8 goals, not more than 8
    tree.add(np.array([0.9, 0.9]), -0.5)
    assert len(tree.leaves) == 2
    left, right = tree.leaves
    assert left.high[0] == pytest.approx(0.0) and right.low[0] == pytest.approx(0.0)
    assert len(left.goals) + len(right.goals) == 9
    assert all(g[0] < 0 for g in left.goals) and all(g[0] >= 0 for g in right.goals)
    assert tree.leaf_for(np.array([-0.5, 0.0])) is left
    # chronological order kept inside each child: left's interest is 0.4
    assert left.interest(4) == pytest.approx(0.4)
    assert tree.interests() == pytest.approx([0.4, 0.0])


# Ten goals on a line, in chronological order. The cut leaving the 2 rightmost goals alone has
# the largest interest gap (right [0, -1]: 0.25; left's last 4 [0, -1, -0.5, -0.5]: 0); the
# middle cut a smaller one (left's last 4 [-0.5, 0, -1, 0]: 0.125; right's: 0).
LINE = np.column_stack([np.linspace(-0.9, 0.9, 10), np.zeros(10)])
LINE_COMPS = np.array([-0.5, -0.5, 0.0, -1.0, 0.0, -1.0, -0.5, -0.5, 0.0, -1.0])


def test_gap_split_takes_the_lopsided_cut():
    choice = best_split(LINE, LINE_COMPS, np.array([-1.0, -1.0]), np.array([1.0, 1.0]),
                        zeta=4, min_per_child=2, min_width=0.0, quality="gap")
    assert choice is not None
    assert (choice.n_left, choice.n_right) == (8, 2)
    assert choice.score == pytest.approx(0.25)


def test_balanced_split_weighs_the_gap_by_the_children_sizes():
    # Baranes & Oudeyer's quality: 5 * 5 * sqrt(0.125) = 8.84 beats 8 * 2 * sqrt(0.25) = 8.
    choice = best_split(LINE, LINE_COMPS, np.array([-1.0, -1.0]), np.array([1.0, 1.0]),
                        zeta=4, min_per_child=2, min_width=0.0, quality="balanced")
    assert choice is not None
    assert (choice.n_left, choice.n_right) == (5, 5)
    assert choice.value == pytest.approx(0.0)
    assert choice.score == pytest.approx(25 * np.sqrt(0.125))


def test_tree_refuses_an_unknown_split_quality():
    with pytest.raises(ValueError, match="split"):
        RegionTree(np.full(2, -1.0), np.full(2, 1.0), max_goals=8, zeta=4, split="widest")
