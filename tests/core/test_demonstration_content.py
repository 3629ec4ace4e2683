"""What a demonstration shows (issue 14, `demonstration_content`): the learner receives exactly
what the mode gives, and no more. On the planar arm."""

from __future__ import annotations

import numpy as np
import pytest

from sgim_nodes.core import runner
from sgim_nodes.core.goal_reaching import GoalAttempt
from sgim_nodes.core.imitation import IMITATION
from sgim_nodes.core.learner_registry import make_learner
from sgim_nodes.core.learners import DEMONSTRATION
from sgim_nodes.core.planar_arm import PlanarArm
from sgim_nodes.core.social_config import SocialConfig
from sgim_nodes.core.teaching import (
    DEMONSTRATION_CONTENTS,
    GOAL_ONLY,
    MEANS_AND_GOAL,
    MEANS_ONLY,
    Demonstration,
)


def test_shown_gives_exactly_the_modes_part():
    demo = Demonstration(3, np.array([0.1, 0.2, 0.3]), np.array([0.5, -0.5]))
    a, y = demo.shown(MEANS_AND_GOAL)
    assert np.array_equal(a, demo.action) and np.array_equal(y, demo.outcome)
    a, y = demo.shown(GOAL_ONLY)
    assert a is None and np.array_equal(y, demo.outcome)
    a, y = demo.shown(MEANS_ONLY)
    assert np.array_equal(a, demo.action) and y is None
    with pytest.raises(ValueError, match="demonstration content"):
        demo.shown("everything")


class _Spy:
    """Records every goal the learner's region tree is given."""

    def __init__(self, learner) -> None:
        self.goals: list[np.ndarray] = []
        add = learner.tree.add

        def recording(goal, competence):
            self.goals.append(np.asarray(goal, dtype=float).copy())
            return add(goal, competence)

        learner.tree.add = recording


def _warm_learner(arm: PlanarArm, movements: int = 60):
    """At least ``movements`` movements, then on to the end of the running attempt, so that
    the demonstration interrupts nothing (an interrupted attempt would record its own goal)."""
    learner = make_learner("sgim-d", arm.action_dim, arm.outcome_dim, 0, None, arm.scale)
    done = 0
    while done < movements or not learner.process.done:
        a, _label = learner.next_action()
        learner.observe(a, arm.execute(a))
        done += 1
    return learner, _Spy(learner)


def _step(learner, arm, n: int) -> list[tuple[np.ndarray, str]]:
    out = []
    for _ in range(n):
        a, label = learner.next_action()
        learner.observe(a, arm.execute(a))
        out.append((a, label))
    return out


def _demo(arm: PlanarArm) -> tuple[np.ndarray, np.ndarray]:
    action = np.full(arm.action_dim, 0.35)
    return action, arm.forward(action)


def test_goal_only_is_emulation_an_attempt_at_the_outcome_never_the_action():
    arm = PlanarArm(seed=0)
    learner, spy = _warm_learner(arm)
    action, outcome = _demo(arm)
    stored = len(learner.memory)
    learner.on_demonstration(None, outcome)
    assert len(learner.memory) == stored  # nothing to store without the action
    first, label = learner.next_action()
    assert isinstance(learner.process, GoalAttempt)  # its own attempt, at the shown goal
    assert np.array_equal(learner.process.goal, outcome)
    learner.observe(first, arm.execute(first))
    moves = [(first, label), *_step(learner, arm, 10)]
    assert all(label != IMITATION for _a, label in moves)
    assert DEMONSTRATION not in learner.memory.labels
    assert spy.goals and np.array_equal(spy.goals[0], outcome)  # the demonstrated goal
    # Never told the action: none of its movements is a variation of it.
    eps = learner.config.imitation_epsilon
    assert min(np.linalg.norm(a - action) for a, _label in moves) > eps


def test_means_only_imitates_the_action_and_is_never_told_its_outcome():
    arm = PlanarArm(seed=0)
    learner, spy = _warm_learner(arm)
    action, outcome = _demo(arm)
    stored = len(learner.memory)
    learner.on_demonstration(action, None)
    assert len(learner.memory) == stored  # the pair is not given: nothing stored yet
    count = learner.config.imitation_count
    moves = _step(learner, arm, count)
    assert [label for _a, label in moves] == [IMITATION] * count
    assert all(np.linalg.norm(a - action) < learner.config.imitation_epsilon
               for a, _label in moves)
    assert DEMONSTRATION not in learner.memory.labels
    # What it knows of the outcome comes from its own casts only: memory grew by exactly the
    # imitations, each with the outcome the arm gave it.
    assert len(learner.memory) == stored + count
    assert not any(np.array_equal(y, outcome) for y in learner.memory.outcomes[stored:])
    assert spy.goals == []  # no goal was given, so no competence for one


def test_means_and_goal_stores_the_pair_and_imitates_it():
    arm = PlanarArm(seed=0)
    learner, spy = _warm_learner(arm)
    action, outcome = _demo(arm)
    learner.on_demonstration(action, outcome)
    assert learner.memory.labels[-1] == DEMONSTRATION
    moves = _step(learner, arm, learner.config.imitation_count)
    assert all(label == IMITATION for _a, label in moves)
    assert spy.goals and np.array_equal(spy.goals[0], outcome)


def test_a_demonstration_must_show_something():
    arm = PlanarArm(seed=0)
    learner, _spy = _warm_learner(arm, 1)
    with pytest.raises(ValueError, match="action, an outcome or both"):
        learner.on_demonstration(None, None)


@pytest.mark.parametrize("content", [
    pytest.param(c, marks=pytest.mark.slow) if c == "means-and-goal" else c
    for c in DEMONSTRATION_CONTENTS])
def test_the_runner_shows_the_learner_only_the_modes_part(content):
    world = runner.build_world("planar-arm", 1)
    learner = runner.make_learner("sgim-d", 12, 2, 1, None, world.scale)
    given: list[tuple] = []
    receive = learner.on_demonstration

    def spy(action, outcome):
        given.append((action, outcome))
        receive(action, outcome)

    learner.on_demonstration = spy
    records: list[dict] = []
    runner.run(learner, world, 300, 0, 1, records.append,
        SocialConfig(demonstration_period=50, tolerance_noise=0.01, demonstration_content=content))
    demos = [r for r in records if r["type"] == "demonstration"]
    assert len(demos) == len(given) == 6
    for record, (action, outcome) in zip(demos, given, strict=True):
        assert record["content"] == content
        assert (action is None) == (content == GOAL_ONLY) == (record["action"] is None)
        assert (outcome is None) == (content == MEANS_ONLY) == (record["outcome"] is None)
        index = record["teaching_index"]
        if action is not None:
            assert np.array_equal(action, world.teaching_actions[index])
        if outcome is not None:
            assert np.array_equal(outcome, world.teaching_outcomes[index])
    labels = [r["label"] for r in records if r["type"] == "movement"]
    assert (IMITATION in labels) == (content != GOAL_ONLY)
    assert (DEMONSTRATION in learner.memory.labels) == (content == MEANS_AND_GOAL)


def test_demo_only_cannot_take_goal_only_demonstrations():
    world = runner.build_world("planar-arm", 0)
    learner = runner.make_learner("demo-only", 12, 2, 0, None, world.scale)
    with pytest.raises(ValueError, match="demo-only"):
        runner.run(learner, world, 10, 0, 0, lambda r: None,
            SocialConfig(demonstration_content=GOAL_ONLY))
    with pytest.raises(SystemExit):
        runner.parse_args(["--learner", "demo-only", "--demonstration-content", "goal-only",
                           "--output", "x.jsonl"])


def test_demo_only_under_means_only_varies_the_action_without_its_outcome():
    world = runner.build_world("planar-arm", 2)
    learner = runner.make_learner("demo-only", 12, 2, 2, None, world.scale)
    records: list[dict] = []
    social = SocialConfig(demonstration_period=40, tolerance_noise=0.01,
                          demonstration_content=MEANS_ONLY)
    runner.run(learner, world, 120, 0, 2, records.append, social)
    assert DEMONSTRATION not in learner.memory.labels
    taught = set(map(tuple, world.teaching_outcomes))
    assert not taught & set(map(tuple, learner.memory.outcomes))
    labels = [r["label"] for r in records if r["type"] == "movement"]
    assert labels == [IMITATION] * 120  # a demonstration at movement 0, varied ever since
