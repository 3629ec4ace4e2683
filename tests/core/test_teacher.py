"""The teacher demonstrates only unreached teaching goals, every P movements."""

import numpy as np
import pytest

from sgim_nodes.core.teaching import Teacher

ACTIONS = np.array([[0.0, 0.0], [0.1, 0.1], [0.2, 0.2]])
OUTCOMES = np.array([[0.0, 0.0], [0.5, 0.5], [-0.5, 0.5]])


def test_due_every_period():
    t = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0), period=150)
    assert [m for m in range(0, 451) if t.due(m)] == [0, 150, 300, 450]


def test_chooses_only_unreached_goals_at_random():
    t = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0), tolerance=0.05)
    reached = np.array([[0.01, 0.0], [0.9, 0.9]])  # goal 0 within 0.05, others not
    assert t.unreached(reached).tolist() == [1, 2]
    picks = [t.choose(reached).index for _ in range(400)]
    assert set(picks) == {1, 2}
    assert np.mean(np.array(picks) == 1) == pytest.approx(0.5, abs=0.1)
    demo = t.choose(reached)
    assert np.array_equal(demo.action, ACTIONS[demo.index])
    assert np.array_equal(demo.outcome, OUTCOMES[demo.index])


def test_tolerance_boundary_and_callable():
    t = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0), tolerance=0.1)
    # distance exactly 0.1 counts as reached ("within" the tolerance)
    assert 1 not in t.unreached(np.array([[0.5, 0.6]])).tolist()
    assert 1 in t.unreached(np.array([[0.5, 0.61]])).tolist()

    def closest(goal):
        return 0.0 if goal[0] < 0 else 1.0  # only goal 2 reached

    assert t.unreached(closest).tolist() == [0, 1]


def test_none_when_everything_is_reached_and_all_when_nothing():
    t = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0))
    assert t.choose(OUTCOMES + 0.01) is None
    assert t.unreached(np.empty((0, 2))).tolist() == [0, 1, 2]


def test_same_seed_same_choices():
    a = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(7))
    b = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(7))
    r = np.empty((0, 2))
    assert [a.choose(r).index for _ in range(20)] == [b.choose(r).index for _ in range(20)]


def test_invalid_teacher():
    with pytest.raises(ValueError):
        Teacher(ACTIONS, OUTCOMES[:2], np.random.default_rng(0))
    with pytest.raises(ValueError):
        Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0), period=0)


def test_a_demonstrated_goal_stays_unreached_until_the_learners_own_movements_reach_it():
    from sgim_nodes.core.learners import make_learner
    from sgim_nodes.core.planar_arm import PlanarArm

    arm = PlanarArm(seed=0)
    learner = make_learner("sgim-d", 12, 2, 0, None, arm.scale)
    goal_action = np.full(12, 0.3)
    goal = arm.forward(goal_action)
    t = Teacher(np.array([goal_action]), np.array([goal]), np.random.default_rng(0),
                tolerance=0.01)
    learner.on_demonstration(goal_action, goal)
    for _ in range(learner.config.imitation_count):  # the imitations land on the goal too
        a, label = learner.next_action()
        assert label == "imitation"
        learner.observe(a, arm.execute(a))
    assert t.choose(learner.own_outcomes()) is not None  # still unreached: shown again
    learner.memory.add(goal_action, goal, "goal_directed")  # its own goal-directed cast
    assert t.choose(learner.own_outcomes()) is None


def test_the_runner_keeps_teaching_while_a_goal_is_unreached():
    import json

    from sgim_nodes.core import runner

    world = runner.build_world("planar-arm", 0)
    learner = runner.make_learner("sgim-d", 12, 2, 0, None, world.scale)
    records: list[dict] = []
    runner.run(learner, world, 600, 0, 0, records.append, teacher_period=50,
               teacher_tolerance_noise=0.01)  # a tolerance too tight to ever reach
    demos = [r for r in records if r["type"] == "demonstration"]
    assert [d["movement"] for d in demos] == list(range(0, 600, 50))
    assert json.dumps(demos[0])  # plain JSON
