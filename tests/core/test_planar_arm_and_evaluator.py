"""The planar arm's kinematics by hand, and the evaluator's bookkeeping."""

import numpy as np
import pytest
from helpers import FlakyWorld, IdentityWorld

from sgim_nodes.core.environment import Environment, Status
from sgim_nodes.core.evaluator import Evaluator
from sgim_nodes.core.learner_registry import make_learner
from sgim_nodes.core.planar_arm import PlanarArm, benchmark_goals, teaching_set


def test_forward_kinematics_hand_values():
    arm = PlanarArm(n_joints=2, max_angle=np.pi / 2)
    assert isinstance(arm, Environment)
    assert arm.forward(np.zeros(2)) == pytest.approx([1.0, 0.0])
    # angles pi/2 then pi/2 + 0: both links point up -> (0, 2) / 2
    assert arm.forward(np.array([1.0, 0.0])) == pytest.approx([0.0, 1.0])
    # pi/2 then pi: (0, 1) + (-1, 0) -> (-0.5, 0.5)
    assert arm.forward(np.array([1.0, 1.0])) == pytest.approx([-0.5, 0.5])
    r = arm.execute(np.array([1.0, 1.0]))
    assert r.status == Status.OK and r.outcome == pytest.approx([-0.5, 0.5])
    assert arm.execute(np.array([0.0, np.nan])).status == Status.INVALID_ACTION
    assert arm.execute(np.zeros(3)).status == Status.INVALID_ACTION


def test_noise_is_seeded():
    a, b = PlanarArm(noise=0.05, seed=3), PlanarArm(noise=0.05, seed=3)
    x = np.full(12, 0.1)
    ya, yb = a.execute(x).outcome, b.execute(x).outcome
    assert np.array_equal(ya, yb) and not np.allclose(ya, a.forward(x))


def test_random_actions_pile_up_but_benchmark_covers_the_reach():
    arm = PlanarArm()
    goals = benchmark_goals(arm)
    assert len(goals) > 50 and np.abs(goals).max() <= 1
    y = arm.forward(np.random.default_rng(0).uniform(-1, 1, (2000, arm.action_dim)))
    # random actions pile up on the stretched side: the left half (x < 0) holds ~40 % of the
    # reachable cells but far fewer random end points
    assert np.mean(y[:, 0] < 0) < 0.6 * np.mean(goals[:, 0] < 0)
    ts = teaching_set(arm, n=27)
    assert ts.actions.shape == (27, 12) and ts.outcomes.shape == (27, 2)
    assert arm.forward(ts.actions) == pytest.approx(ts.outcomes)


def test_evaluator_hand_distances_and_own_world():
    goals = np.array([[0.0, 0.0], [0.5, 0.5], [-0.5, 0.2]])
    ev = Evaluator(IdentityWorld(), goals)
    res = ev.evaluate(lambda g: g + np.array([0.3, 0.4]))  # always 0.5 away
    assert res.distances == pytest.approx([0.5, 0.5, 0.5])
    assert res.mean_distance == pytest.approx(0.5)
    flaky = Evaluator(FlakyWorld(IdentityWorld(), every=2), goals, failure_distance=9.0)
    res = flaky.evaluate(lambda g: g)
    assert res.failed.tolist() == [False, True, False]
    assert res.distances == pytest.approx([0.0, 9.0, 0.0]) and res.mean_distance == 3.0


def test_evaluation_does_not_count_or_learn():
    train = PlanarArm(seed=0)
    learner = make_learner("saggriac", 12, 2, 0, None, train.scale)
    for _ in range(100):
        a, _ = learner.next_action()
        learner.observe(a, train.execute(a))
    n_mem, n_mov = len(learner.memory), learner.n_movements
    eval_world = IdentityWorld(12)
    Evaluator(eval_world, benchmark_goals(train, cells=6)).evaluate(learner.inverse)
    assert eval_world.calls > 0
    assert len(learner.memory) == n_mem and learner.n_movements == n_mov


def test_evaluator_measures_a_touchdown_without_outcome_to_where_it_came_down():
    from dataclasses import dataclass

    @dataclass
    class LandResult:  # like the fishing world's hook on land: no outcome, a touch-down point
        outcome: None
        status: int
        touchdown: np.ndarray

    class LandWorld(IdentityWorld):
        def execute(self, action):
            return LandResult(None, 1, np.asarray(action, float)[:2] + 0.1)

    goals = np.array([[0.0, 0.0], [0.5, -0.5]])
    res = Evaluator(LandWorld(), goals, failure_distance=9.0).evaluate(lambda g: g)
    assert res.distances == pytest.approx([np.hypot(0.1, 0.1)] * 2)
    assert not res.failed.any()
    assert res.reached == pytest.approx(goals + 0.1)
