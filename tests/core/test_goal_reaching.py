"""One goal attempt: exploration rate, stopping rules, every movement counted."""

import numpy as np
import pytest
from helpers import ConstantWorld, IdentityWorld

from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.environment import MovementResult, Status
from sgim_nodes.core.goal_reaching import GoalAttempt, exploration_probability
from sgim_nodes.core.inverse_model import InverseModel
from sgim_nodes.core.memory import Memory


def _setup(config, n=1):
    mem = Memory(2, 2)
    rng = np.random.default_rng(0)
    for _ in range(n):
        a = rng.uniform(-0.2, 0.2, 2) if n > 1 else np.zeros(2)
        mem.add(a, a.copy())
    inv = InverseModel(mem, config.l_max, config.k_max, config.alpha, config.interpolation_sigma)
    return mem, inv


def test_exploration_probability_hand_values():
    assert exploration_probability(0.1, gain=2.0, cap=0.5) == pytest.approx(0.2)
    assert exploration_probability(1.0, gain=2.0, cap=0.5) == 0.5
    assert exploration_probability(0.0, gain=2.0, cap=0.5) == 0.0
    assert exploration_probability(float("inf"), gain=2.0, cap=0.5) == 1.0


@pytest.mark.parametrize(("goal_x", "expected"), [(0.1, 0.2), (0.05, 0.1), (0.6, 0.5)])
def test_exploration_rate(goal_x, expected):
    cfg = LearnerConfig(explore_gain=2.0, explore_cap=0.5)
    mem, inv = _setup(cfg)  # one outcome at the origin
    rng = np.random.default_rng(42)
    n = 5000
    explored = [GoalAttempt(np.array([goal_x, 0.0]), mem, inv, cfg, rng, 2).explore
                for _ in range(n)]
    tol = 4 * np.sqrt(expected * (1 - expected) / n)
    assert np.mean(explored) == pytest.approx(expected, abs=tol)


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


def test_stops_when_the_goal_is_reached():
    cfg = LearnerConfig(explore_gain=0.0, goal_budget=10)
    mem, inv = _setup(cfg, n=20)
    goal = np.array([0.05, -0.05])
    att = GoalAttempt(goal, mem, inv, cfg, np.random.default_rng(0), 2)
    labels = _run(att, IdentityWorld(), mem)
    assert labels[0] == "goal_directed"
    assert 1 <= len(labels) < 10
    assert att.best_distance < cfg.reach_threshold
    assert len(mem) == 20 + len(labels)  # every movement stored


def test_budget_spent_when_unreachable_and_nelder_mead_moves():
    cfg = LearnerConfig(explore_gain=0.0, goal_budget=7)
    mem, inv = _setup(cfg, n=20)
    world = ConstantWorld([0.5, 0.5])
    att = GoalAttempt(np.array([-0.9, -0.9]), mem, inv, cfg, np.random.default_rng(0), 2)
    labels = _run(att, world, mem)
    assert labels == ["goal_directed"] * 7
    assert world.calls == 7 and att.movements == 7
    assert att._nm is not None and att._nm.n_evaluations == 6  # first action + 6 NM asks


def test_failed_movements_count_against_the_budget():
    cfg = LearnerConfig(explore_gain=0.0, goal_budget=4)
    mem, inv = _setup(cfg, n=5)
    att = GoalAttempt(np.array([0.5, 0.5]), mem, inv, cfg, np.random.default_rng(0), 2)
    n = 0
    while not att.done:
        a, _ = att.next_action()
        att.observe(a, MovementResult(None, Status.NO_CONTACT))
        n += 1
    assert n == 4 and att.best_outcome is None
    assert att._nm.n_evaluations == 3  # movements 2..4 were told to Nelder-Mead
    assert att._nm.best_f < cfg.failure_cost  # memory vertices beat every failure


def test_empty_memory_explores():
    cfg = LearnerConfig()
    mem = Memory(3, 2)
    inv = InverseModel(mem, 3, 2, 0.5, 0.05)
    att = GoalAttempt(np.zeros(2), mem, inv, cfg, np.random.default_rng(0), 3)
    a, label = att.next_action()
    assert label == "exploration" and a.shape == (3,)
    att.observe(a, MovementResult(np.array([0.1, 0.0]), Status.OK))
    assert att.done and att.movements == 1
    assert att.best_distance == pytest.approx(0.1)
