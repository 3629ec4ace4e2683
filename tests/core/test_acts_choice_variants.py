"""SGIM-ACTS's two choice switches: the defaults draw as the lineage's choice always drew,
``gain`` values a pair by its recent gain (an untried one the most), ``region-first`` chooses
the goal as SAGG-RIAC does and then the leaf's best strategy, and all four run."""

import json

import numpy as np
import pytest

from sgim_nodes.core.acts_runner import experts_for, run_acts
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.goal_selection import MODES, GoalSelector, region_probabilities
from sgim_nodes.core.learner_registry import make_learner
from sgim_nodes.core.region_tree import RegionTree
from sgim_nodes.core.runner import build_world
from sgim_nodes.core.strategies import Strategy
from sgim_nodes.core.strategy_choice import PairChoice, StrategyChooser, pair_probabilities
from sgim_nodes.core.strategy_regions import UNTRIED_GAIN, StrategyRegions

A, B, C = "autonomous", "mimicry:t", "emulation:t"
NAMES = (A, B, C)
RADIUS = 0.05


def regions(max_goals=40, zeta=10, min_per_child=3):
    tree = RegionTree(np.array([-1.0, -1.0]), np.array([1.0, 1.0]), max_goals, zeta,
                      min_per_child=min_per_child, min_width=0.05)
    return StrategyRegions(tree, NAMES)


def strategies(cost_a=1.0, cost_b=1.0, cost_c=1.0):
    return (Strategy("autonomous", None, cost_a), Strategy("mimicry", "t", cost_b),
            Strategy("emulation", "t", cost_c))


def chooser(r, costs=(1.0, 1.0, 1.0), p=(1.0, 0.0, 0.0), **switches):
    return StrategyChooser(r, strategies(*costs), p, RADIUS, **switches)


def fill(r, strategy, competences, point=(0.2, 0.2)):
    for c in competences:
        r.add(strategy, np.array(point), c)


def lineage_sample(ch: StrategyChooser, rng: np.random.Generator) -> PairChoice:
    """The lineage's choice as it was written before the switches existed (a frozen copy)."""
    mode = int(rng.choice(MODES, p=ch.p_modes))
    leaves = ch.regions.leaves
    root = ch.regions.tree.root
    if mode == 2:
        strategy = ch.strategies[int(rng.integers(len(ch.strategies)))]
        goal = rng.uniform(root.low, root.high)
        leaf = ch.regions.tree.leaf_for(goal)
        return PairChoice(strategy, goal, 2, leaves.index(leaf), leaf)
    weights = ch.regions.interests() / ch.costs[None, :]
    volumes = np.array([leaf.volume for leaf in leaves])
    fallback = volumes[:, None] / ch.costs[None, :]
    probs = pair_probabilities(weights, fallback)
    k = int(rng.choice(len(probs), p=probs))
    i, j = divmod(k, len(ch.strategies))
    region, strategy = leaves[i], ch.strategies[j]
    history = ch.regions.history(strategy.name, region)
    if mode == 1 or not history.goals:
        return PairChoice(strategy, rng.uniform(region.low, region.high), mode, i, region)
    worst = history.goals[int(np.argmin(history.competences))]
    goal = np.clip(worst + rng.uniform(-RADIUS, RADIUS, size=worst.shape), region.low,
                   region.high)
    return PairChoice(strategy, goal, 3, i, region)


# --- the defaults ---

@pytest.mark.parametrize("switches", [{}, {"order": "pair", "value": "interest"}])
def test_the_defaults_draw_exactly_as_the_lineages_choice_did(switches):
    """Same seed, same regions as they grow and split: the same pairs, goals and modes."""
    r = regions(max_goals=30)
    ch = chooser(r, (1.0, 10.0, 5.0), (0.6, 0.2, 0.2), **switches)
    new, old = np.random.default_rng(11), np.random.default_rng(11)
    for _ in range(300):
        got, want = ch.sample(new), lineage_sample(ch, old)
        assert (got.strategy, got.mode, got.region_index) == (
            want.strategy, want.mode, want.region_index)
        assert got.region is want.region and np.array_equal(got.goal, want.goal)
        # progress that depends on where and how, so the pairs' interests differ
        step = {A: 0.002, B: 0.004, C: 0.0}[got.strategy.name]
        comp = -1.0 + min(1.0, step * len(r.history(got.strategy.name, got.region)))
        r.add(got.strategy.name, got.goal, comp * (1.0 if got.goal[0] < 0 else 0.5))
    assert len(r.leaves) > 2  # the comparison went through splits


def test_learners_and_the_graph_build_their_chooser_with_the_configured_switches():
    cfg = LearnerConfig(strategy_choice_order="region-first", strategy_value="gain")
    world = build_world("planar-arm", 0, arm_joints=7)
    made = make_learner("sgim-acts", 7, 2, 0, cfg, world.scale, teachers=("t",))
    assert (made.chooser.order, made.chooser.value) == ("region-first", "gain")
    default = make_learner("sgim-acts", 7, 2, 0, None, world.scale, teachers=("t",))
    assert (default.chooser.order, default.chooser.value) == ("pair", "interest")


@pytest.mark.ros
def test_the_goal_generator_builds_its_chooser_from_the_config():
    from sgim_nodes.core.planar_arm import PlanarArm
    from sgim_nodes.nodes.goal_generator import acts_choice

    cfg = LearnerConfig(strategy_choice_order="region-first", strategy_value="gain")
    _, ch = acts_choice(cfg, PlanarArm(n_joints=7, seed=0).scale, "west,east")
    assert (ch.order, ch.value) == ("region-first", "gain")


# --- the gain value ---

def test_the_gain_is_the_mean_of_one_plus_competence_over_the_last_zeta_episodes():
    r = regions(zeta=10)
    fill(r, A, [0.0] * 10 + [-0.8] * 10)  # good long ago, poor over the last zeta
    fill(r, B, [-0.5] * 5)
    leaf = r.leaves[0]
    assert r.gain(A, leaf) == pytest.approx(0.2)  # not 0.6: the old successes are out
    assert r.gain(B, leaf) == pytest.approx(0.5)
    assert r.gain(C, leaf) == UNTRIED_GAIN == 1.0
    assert r.gains()[0] == pytest.approx([0.2, 0.5, 1.0])
    # with the untried pair made dear, B's recent gain beats A's older one, both ways
    costs = (1.0, 1.0, 10.0)
    rng = np.random.default_rng(0)
    first = chooser(r, costs, order="region-first", value="gain")
    assert {first.sample(rng).strategy.name for _ in range(50)} == {B}
    pair = chooser(r, costs, value="gain")  # eq. 3 on (0.2, 0.5, 0.1)
    assert pair.probabilities()[0] == pytest.approx([0.2, 0.8, 0.0])


@pytest.mark.parametrize("order", ["pair", "region-first"])
def test_an_untried_pair_is_chosen_before_a_tried_one_with_low_gain(order):
    r = regions()
    fill(r, A, [-0.9] * 10)  # the learner's own gain is low here: 0.1
    fill(r, C, [-0.2] * 10)  # the emulation pair gains 0.8, but at cost 10: 0.08
    ch = chooser(r, (1.0, 4.0, 10.0), order=order, value="gain")  # untried B: 1 / 4
    assert ch.weights()[0] == pytest.approx([0.1, 0.25, 0.08])
    rng = np.random.default_rng(1)
    picks = [ch.sample(rng).strategy.name for _ in range(200)]
    if order == "region-first":  # the leaf's best, every time
        assert set(picks) == {B}
    else:  # eq. 3 on the same weights: B most, never the minimum
        assert ch.probabilities()[0] == pytest.approx([0.02 / 0.19, 0.17 / 0.19, 0])
        assert picks.count(B) > picks.count(A) and C not in picks
    interest = chooser(r, (1.0, 4.0, 10.0), order=order)  # eq. 2 sees no progress at all
    picks = [interest.sample(rng).strategy.name for _ in range(200)]
    assert picks.count(B) < 100  # ties or volume / cost: the untried pair gets no favour


@pytest.mark.parametrize("cost_b, best", [(4.0, A), (1.5, B)])
def test_the_pair_of_higher_mean_gain_over_cost_wins(cost_b, best):
    """B gains more (0.9 against 0.5) but must be worth its cost: 0.9 / 4 loses to 0.5 / 1,
    0.9 / 1.5 wins."""
    r = regions()
    fill(r, A, [-0.5] * 10)
    fill(r, B, [-0.1] * 10)
    fill(r, C, [-1.0] * 10)
    first = chooser(r, (1.0, cost_b, 1.0), order="region-first", value="gain")
    rng = np.random.default_rng(2)
    assert {first.sample(rng).strategy.name for _ in range(100)} == {best}
    pair = chooser(r, (1.0, cost_b, 1.0), value="gain")  # eq. 3: the better, the likelier
    p = dict(zip(NAMES, pair.probabilities().ravel(), strict=True))
    assert p[best] == max(p.values()) and p[C] == 0.0


# --- region-first ---

def two_leaves():
    """Two leaves split at x = 0 (by a third strategy's constant goals): on the left the
    pooled competences jump (A fails, then B succeeds), so the region's interest is high
    while each pair's own history is constant; on the right A rises while B falls, so each
    pair progresses while the pooled window does not move."""
    r = regions(max_goals=24, zeta=10)
    rng = np.random.default_rng(7)
    for k in range(25):
        r.add(C, np.array([-0.5 if k % 2 else 0.5, rng.uniform(-0.9, 0.9)]), -1.0)
    assert len(r.leaves) == 2 and r.tree.root.split_dim == 0
    for _ in range(5):
        r.add(A, np.array([-0.5, rng.uniform(-0.9, 0.9)]), -1.0)
    for _ in range(5):
        r.add(B, np.array([-0.5, rng.uniform(-0.9, 0.9)]), 0.0)
    for a, b in zip(np.linspace(-1, 0, 5), np.linspace(0, -1, 5), strict=True):
        r.add(A, np.array([0.5, rng.uniform(-0.9, 0.9)]), a)
        r.add(B, np.array([0.5, rng.uniform(-0.9, 0.9)]), b)
    assert len(r.leaves) == 2
    return r


def test_region_first_mode_one_draws_the_leaf_by_region_interest_not_by_the_pairs():
    r = two_leaves()
    left = r.leaves[0]
    assert r.tree.interests() == pytest.approx([0.5, 0.0])
    assert r.interests()[0] == pytest.approx([0, 0, 0]) and min(r.interests()[1][:2]) > 0
    volumes = np.array([leaf.volume for leaf in r.leaves])
    assert region_probabilities(r.tree.interests(), volumes) == pytest.approx([1.0, 0.0])
    costs = (1.0, 2.0, 3.0)  # one best strategy per leaf: no tie draws
    first = chooser(r, costs, order="region-first", value="gain")
    sagg = GoalSelector(r.tree, (1.0, 0.0, 0.0), RADIUS)
    rng, same = np.random.default_rng(3), np.random.default_rng(3)
    for _ in range(200):
        got, goal = first.sample(rng), sagg.sample(same)
        assert np.array_equal(got.goal, goal.goal)  # SAGG-RIAC's very goal
        assert (got.mode, got.region_index, got.region) == (1, goal.region_index, left)
        assert got.strategy.name == B  # the left leaf's best gain / cost
    pair = chooser(r, costs)  # the lineage's draw follows the pairs' interest: right
    assert {pair.sample(rng).region_index for _ in range(200)} == {1}


def test_region_first_mode_two_takes_the_goals_leaf_best_strategy_never_a_random_one():
    r = two_leaves()
    left, right = r.leaves
    costs = (1.0, 2.0, 3.0)
    ch = chooser(r, costs, p=(0.0, 1.0, 0.0), order="region-first", value="gain")
    best = {id(left): B, id(right): A}
    rng = np.random.default_rng(4)
    picks = [ch.sample(rng) for _ in range(300)]
    for p in picks:
        assert p.mode == 2 and r.tree.leaf_for(p.goal) is p.region
        assert p.region_index == r.leaves.index(p.region)
        assert p.strategy.name == best[id(p.region)]
    goals = np.array([p.goal for p in picks])
    assert goals.min() >= -1 and goals.max() <= 1 and goals.std(axis=0).min() > 0.4
    assert {id(p.region) for p in picks} == {id(left), id(right)}
    lineage = chooser(r, costs, p=(0.0, 1.0, 0.0))  # draws its strategies uniformly
    assert {lineage.sample(rng).strategy.name for _ in range(100)} == set(NAMES)


def test_region_first_mode_three_probes_near_the_leafs_least_competent_goal():
    """SAGG-RIAC's mode 3: near the worst of the leaf's pooled goals, whichever strategy
    attempted it, not near the chosen strategy's own worst."""
    r = regions()
    worst = np.array([-0.6, 0.7])
    fill(r, B, [-1.0], worst)
    fill(r, B, [-0.1] * 9, (0.5, -0.5))
    fill(r, A, [-0.5] * 10, (0.9, 0.9))  # A's own worst is there
    ch = chooser(r, (1.0, 10.0, 10.0), p=(0.0, 0.0, 1.0), order="region-first",
                 value="gain")
    rng = np.random.default_rng(5)
    for _ in range(50):
        choice = ch.sample(rng)
        assert choice.mode == 3 and choice.strategy.name == A
        assert np.abs(choice.goal - worst).max() <= RADIUS


def test_region_first_draws_among_equally_good_strategies_from_the_given_stream():
    r = regions()
    fill(r, A, [-0.5] * 10)
    fill(r, B, [-0.5] * 10)
    fill(r, C, [-1.0] * 10)
    ch = chooser(r, order="region-first", value="gain")

    def names(seed):
        rng = np.random.default_rng(seed)
        return [ch.sample(rng).strategy.name for _ in range(60)]

    assert set(names(6)) == {A, B}  # the tie, both ways; never the worse C
    assert names(6) == names(6) and names(6) != names(8)


# --- refusals ---

@pytest.mark.parametrize("field, value, allowed", [
    ("strategy_choice_order", "region", "pair, region-first"),
    ("strategy_choice_order", "Pair", "pair, region-first"),
    ("strategy_value", "progress", "interest, gain"),
    ("strategy_value", "", "interest, gain"),
])
def test_the_config_refuses_unknown_choice_switches_naming_what_it_takes(field, value,
                                                                          allowed):
    with pytest.raises(ValueError, match=rf"LearnerConfig\.{field}: must be one of {allowed} "
                                         rf"\(got '{value}'\)"):
        LearnerConfig(**{field: value})


def test_the_chooser_refuses_unknown_switches():
    with pytest.raises(ValueError, match="order must be one of pair, region-first"):
        chooser(regions(), order="who-first")
    with pytest.raises(ValueError, match="value must be one of interest, gain"):
        chooser(regions(), value="cost")


# --- the four combinations, run ---

def acts_run(order, value, seed=3, movements=300):
    world = build_world("planar-arm", seed, arm_joints=7)
    experts = experts_for("planar-arm", world, seed)
    cfg = LearnerConfig(strategy_choice_order=order, strategy_value=value)
    made = make_learner("sgim-acts", 7, 2, seed, cfg, world.scale, teachers=tuple(experts))
    records = []
    run_acts(made, world, movements, 0, experts, records.append)
    return made, records


def test_each_combination_of_the_switches_runs_its_own_run():
    runs = {}
    for order in ("pair", "region-first"):
        for value in ("interest", "gain"):
            made, records = acts_run(order, value)
            movements = [r for r in records if r["type"] == "movement"]
            assert len(movements) == 300
            names = {s.name for s in made.strategies}
            choices = [r for r in records if r["type"] == "strategy_choice"]
            assert choices and {c["strategy"] for c in choices} <= names
            assert {c["mode"] for c in choices} <= set(MODES)
            assert made.regions.counts().sum() == sum(c.competence is not None
                                                      for c in made.choices)
            runs[order, value] = json.dumps(movements)
    assert len(set(runs.values())) == 4  # each switch changes what the learner does
