"""Competence per (strategy, region) and the three-mode choice of a pair, by interest / cost."""

import numpy as np
import pytest

from sgim_nodes.core.region_tree import RegionTree, interest
from sgim_nodes.core.strategies import Strategy
from sgim_nodes.core.strategy_choice import StrategyChooser, pair_probabilities
from sgim_nodes.core.strategy_regions import StrategyRegions

NAMES = ("autonomous", "mimicry:t")


def regions(max_goals=40, zeta=10):
    tree = RegionTree(np.array([-1.0, -1.0]), np.array([1.0, 1.0]), max_goals, zeta,
                      min_per_child=3, min_width=0.05)
    return StrategyRegions(tree, NAMES)


def strategies(cost_auto=1.0, cost_mimic=4.0):
    return (Strategy("autonomous", None, cost_auto), Strategy("mimicry", "t", cost_mimic))


def test_each_pair_keeps_its_own_history_and_interest():
    r = regions()
    rising = np.linspace(-1, 0, 10)
    for c in rising:  # autonomous progresses, mimicry stays put, in the same region
        r.add("autonomous", np.array([0.2, 0.2]), c)
        r.add("mimicry:t", np.array([0.3, 0.1]), -1.0)
    leaf = r.leaves[0]
    assert r.history("autonomous", leaf).competences == pytest.approx(list(rising))
    assert r.interest("autonomous", leaf) == pytest.approx(interest(rising, 10))
    assert r.interest("autonomous", leaf) > 0
    assert r.interest("mimicry:t", leaf) == 0.0
    assert r.counts().tolist() == [[10, 10]]


def test_a_split_divides_every_strategys_history_by_the_same_cut_in_order():
    r = regions(max_goals=40)
    rng = np.random.default_rng(0)
    added = []
    for k in range(41):  # the 41st pooled goal splits the root
        name = NAMES[k % 2]
        left = k % 4 < 2
        goal = np.array([-0.5 if left else 0.5, rng.uniform(-1, 1)])
        comp = -1.0 if left else -1.0 + k / 41  # progress on the right only
        r.add(name, goal, comp)
        added.append((name, goal, comp))
    assert len(r.leaves) == 2
    total = r.counts().sum()
    assert total == 41 == sum(len(leaf.goals) for leaf in r.leaves)
    for leaf in r.leaves:
        for name in NAMES:
            expected = [c for n, g, c in added if n == name and leaf.contains(g)]
            assert r.history(name, leaf).competences == expected  # kept in order


def test_weights_are_interest_divided_by_cost_per_pair():
    r = regions()
    for c in np.linspace(-1, 0, 10):
        r.add("autonomous", np.array([0.2, 0.2]), c)
        r.add("mimicry:t", np.array([0.2, 0.2]), c)  # the same progress...
    chooser = StrategyChooser(r, strategies(1.0, 4.0), (1.0, 0.0, 0.0), 0.05)
    w = chooser.weights()
    assert w.shape == (1, 2)
    assert w[0, 0] == pytest.approx(r.interest("autonomous", r.leaves[0]))
    assert w[0, 1] == pytest.approx(w[0, 0] / 4.0)  # ...at four times the cost


def test_mode_one_draws_pairs_in_proportion_to_interest_over_cost():
    r = regions()
    for c in np.linspace(-1, 0, 10):
        r.add("autonomous", np.array([0.2, 0.2]), c)
        r.add("mimicry:t", np.array([0.2, 0.2]), 2 * c / 3)  # less progress
    chooser = StrategyChooser(r, strategies(1.0, 1.0), (1.0, 0.0, 0.0), 0.05)
    p = chooser.probabilities()
    assert p.sum() == pytest.approx(1.0)
    w = chooser.weights().ravel()
    assert p.ravel() == pytest.approx((w - w.min()) / (w - w.min()).sum())
    rng = np.random.default_rng(1)
    picks = [chooser.sample(rng).strategy.name for _ in range(200)]
    assert picks.count("autonomous") == 200  # the other pair is the minimum: weight 0


def test_without_any_interest_mode_one_prefers_the_cheap_strategy_by_cost():
    chooser = StrategyChooser(regions(), strategies(1.0, 4.0), (1.0, 0.0, 0.0), 0.05)
    assert chooser.probabilities().ravel() == pytest.approx([0.8, 0.2])
    assert pair_probabilities(np.zeros(3), np.array([1.0, 1.0, 2.0])) == pytest.approx(
        [0.25, 0.25, 0.5])


def test_mode_two_draws_strategies_uniformly_and_goals_in_the_whole_box():
    r = regions()
    for c in np.linspace(-1, 0, 10):
        r.add("autonomous", np.array([0.2, 0.2]), c)
    chooser = StrategyChooser(r, strategies(1.0, 100.0), (0.0, 1.0, 0.0), 0.05)
    rng = np.random.default_rng(2)
    picks = [chooser.sample(rng) for _ in range(400)]
    share = np.mean([p.strategy.name == "mimicry:t" for p in picks])
    assert 0.4 < share < 0.6  # cost and interest play no part in mode 2
    goals = np.array([p.goal for p in picks])
    assert goals.min() >= -1 and goals.max() <= 1 and goals.std(axis=0).min() > 0.4
    assert {p.mode for p in picks} == {2}


def test_mode_three_probes_near_that_strategys_least_competent_goal():
    r = regions()
    worst = np.array([-0.6, 0.7])
    for k, c in enumerate(np.linspace(-0.9, 0, 10)):
        r.add("mimicry:t", worst if k == 0 else np.array([0.5, -0.5]), c)
        r.add("autonomous", np.array([0.9, 0.9]), -1.0)  # its worst is elsewhere
    chooser = StrategyChooser(r, strategies(1.0, 1.0), (0.0, 0.0, 1.0), 0.05)
    rng = np.random.default_rng(3)
    for _ in range(50):
        choice = chooser.sample(rng)
        assert choice.mode == 3 and choice.strategy.name == "mimicry:t"
        assert np.abs(choice.goal - worst).max() <= 0.05


def test_bad_setups_are_refused():
    tree = RegionTree(np.zeros(2), np.ones(2), 10, 4)
    with pytest.raises(ValueError, match="distinct"):
        StrategyRegions(tree, ("a", "a"))
    r = StrategyRegions(tree, NAMES)
    with pytest.raises(ValueError, match="unknown strategy 'emulation:t'"):
        r.add("emulation:t", np.zeros(2), -1.0)
    with pytest.raises(ValueError, match="the regions keep"):
        StrategyChooser(r, strategies()[::-1], (1.0, 0.0, 0.0), 0.05)
