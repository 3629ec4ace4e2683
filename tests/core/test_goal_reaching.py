"""One goal attempt: the paper's exploration rule, local exploration, stopping rules, budget."""

import numpy as np
import pytest
from helpers import ConstantWorld, IdentityWorld

from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.environment import MovementResult, Status
from sgim_nodes.core.goal_reaching import (
    GoalAttempt,
    exploration_probability,
    exploration_width,
    probe_scale_for,
)
from sgim_nodes.core.learners import inverse_model_for
from sgim_nodes.core.memory import Memory
from sgim_nodes.core.scale import unit_box

SCALE = unit_box(2, 0.02)


def _setup(config, n=1, action_dim=2):
    mem = Memory(action_dim, 2)
    rng = np.random.default_rng(0)
    for _ in range(n):
        a = rng.uniform(-0.2, 0.2, action_dim) if n > 1 else np.zeros(action_dim)
        mem.add(a, np.clip(a[:2], -1, 1))
    return mem, inverse_model_for(mem, config, SCALE)


def _attempt(goal, mem, inv, cfg, seed=0, action_dim=2):
    return GoalAttempt(np.asarray(goal, float), mem, inv, cfg, SCALE,
                       np.random.default_rng(seed), action_dim,
                       probe_scale_for(cfg, SCALE, action_dim))


def test_exploration_probability_and_width_hand_values():
    assert exploration_probability(0.1, gain=2.0, cap=0.5) == pytest.approx(0.2)
    assert exploration_probability(0.1, gain=4.0, cap=0.5, size=2.0) == pytest.approx(0.2)
    assert exploration_probability(1.0, gain=2.0, cap=0.5) == 0.5
    assert exploration_probability(0.0, gain=2.0, cap=0.5) == 0.0
    assert exploration_probability(float("inf"), gain=2.0, cap=0.5) == 1.0
    assert exploration_width(0.1, full_width=0.3, full_distance=0.5) == pytest.approx(0.06)
    assert exploration_width(2.0, full_width=0.3, full_distance=0.5) == pytest.approx(0.3)


@pytest.mark.parametrize(("goal_x", "expected"), [(0.1, 0.2), (0.05, 0.1), (0.6, 0.5)])
def test_exploration_rate_follows_the_papers_rule(goal_x, expected):
    cfg = LearnerConfig(explore_gain=4.0, explore_cap=0.5)  # 4 per box side of 2: 2 per unit
    mem, inv = _setup(cfg)  # one outcome at the origin
    n = 3000
    explored = [_attempt([goal_x, 0.0], mem, inv, cfg, seed=s).explore for s in range(n)]
    tol = 4 * np.sqrt(expected * (1 - expected) / n)
    assert np.mean(explored) == pytest.approx(expected, abs=tol)


def test_exploring_perturbs_the_best_known_action_more_the_farther_the_goal():
    cfg = LearnerConfig(explore_gain=1e6, explore_cap=1.0, explore_action=0.3,
                        explore_distance_size=0.5)  # always explore; full width at 1.0
    mem, inv = _setup(cfg, action_dim=8)
    spreads = []
    for goal_x in (0.05, 0.8):
        steps = []
        for seed in range(300):
            att = _attempt([goal_x, 0.0], mem, inv, cfg, seed=seed, action_dim=8)
            a, label = att.next_action()
            assert label == "exploration"
            steps.append(a - att._estimate.action)
        spreads.append(np.std(steps))
    assert spreads[0] == pytest.approx(0.3 * 0.05, rel=0.15)  # width grows with the distance
    assert spreads[1] == pytest.approx(0.3 * 0.8, rel=0.15)


def _run(attempt, world, mem):
    labels = []
    while not attempt.done:
        a, label = attempt.next_action()
        assert a.min() >= -1 and a.max() <= 1
        labels.append(label)
        r = world.execute(a)
        if r.status == Status.OK:
            mem.add(a, r.outcome, label)
        attempt.observe(a, r)
    return labels


@pytest.mark.parametrize("optimiser", ["subspace", "local-linear", "nelder-mead",
                                       "random-search"])
def test_stops_when_the_goal_is_reached(optimiser):
    cfg = LearnerConfig(explore_gain=0.0, goal_budget=10, optimiser=optimiser,
                        attempt_patience=10)
    mem, inv = _setup(cfg, n=60)  # enough casts around each action for the local fits
    goal = np.array([0.3, -0.25])  # outside the memory's [-0.2, 0.2] box
    att = _attempt(goal, mem, inv, cfg)
    labels = _run(att, IdentityWorld(), mem)
    assert labels[0] == "goal_directed" and att.start_distance > 0.05
    assert att.best_distance < att.start_distance  # it gained on memory
    assert len(mem) == 60 + len(labels)  # every movement stored
    if att.best_distance < cfg.distances(SCALE).reach_threshold:
        assert len(labels) < 10


def test_patience_ends_a_hopeless_attempt_and_the_budget_caps_it():
    cfg = LearnerConfig(explore_gain=0.0, goal_budget=7, attempt_patience=3)
    mem, inv = _setup(cfg, n=20)
    world = ConstantWorld([0.5, 0.5])  # the goal cannot be approached at all
    att = _attempt([-0.9, -0.9], mem, inv, cfg)
    labels = _run(att, world, mem)
    assert labels == ["goal_directed"] * 4  # the first cast, then 3 without a new best
    cfg = LearnerConfig(explore_gain=0.0, goal_budget=7, attempt_patience=100)
    att = _attempt([-0.9, -0.9], mem, inv, cfg)
    assert len(_run(att, ConstantWorld([0.5, 0.5]), mem)) == 7


def test_failed_movements_count_against_the_budget():
    cfg = LearnerConfig(explore_gain=0.0, goal_budget=4, attempt_patience=100)
    mem, inv = _setup(cfg, n=5)
    att = _attempt([0.5, 0.5], mem, inv, cfg)
    n = 0
    while not att.done:
        a, _ = att.next_action()
        att.observe(a, MovementResult(None, Status.NO_CONTACT))
        n += 1
    assert n == 4 and att.best_outcome is None


def test_empty_memory_explores_with_a_random_action():
    cfg = LearnerConfig()
    mem = Memory(3, 2)
    att = _attempt(np.zeros(2), mem, inverse_model_for(mem, cfg, SCALE), cfg,
                   action_dim=3)
    a, label = att.next_action()
    assert label == "exploration" and a.shape == (3,)
    att.observe(a, MovementResult(np.array([0.1, 0.0]), Status.OK))
    assert att.done and att.movements == 1
    assert att.best_distance == pytest.approx(0.1)
