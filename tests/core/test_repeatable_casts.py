"""core/repeatable_casts.py: a cast's noise is fixed by its key, so a cast made again would
land where the first did; it is not made again, and nothing measured changes for it."""

from __future__ import annotations

import numpy as np

from sgim_nodes.core.evaluator import Evaluator
from sgim_nodes.core.planar_arm import PlanarArm
from sgim_nodes.core.repeatable_casts import RepeatableCasts, goal_key


class Counting(PlanarArm):
    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.casts = 0

    def execute(self, action):
        self.casts += 1
        return super().execute(action)


def test_the_same_action_for_the_same_key_is_cast_once_and_lands_the_same():
    arm = Counting(n_joints=5, noise=0.05, seed=3)
    casts = RepeatableCasts(arm)
    a, b = np.full(5, 0.2), np.full(5, -0.3)
    first = casts.execute(b"goal-1", a)
    assert casts.execute(b"goal-1", a) is first and arm.casts == 1 and casts.saved == 1
    other = casts.execute(b"goal-1", b)  # another answer: cast, and kept instead
    assert arm.casts == 2 and not np.array_equal(other.outcome, first.outcome)
    again = casts.execute(b"goal-1", a)  # back to the first answer: the first cast's noise
    assert arm.casts == 3 and np.array_equal(again.outcome, first.outcome)
    elsewhere = casts.execute(b"goal-2", a)  # another key: other noise
    assert not np.array_equal(elsewhere.outcome, first.outcome)


def test_an_environment_without_reseed_is_cast_every_time():
    class Plain:
        action_dim, outcome_dim = 2, 2

        def __init__(self) -> None:
            self.casts = 0

        def execute(self, action):
            self.casts += 1
            return action

    env = Plain()
    casts = RepeatableCasts(env)
    casts.execute(b"k", np.zeros(2))
    casts.execute(b"k", np.zeros(2))
    assert env.casts == 2 and casts.saved == 0


def test_an_evaluation_is_the_same_whether_its_casts_are_kept_or_made_afresh():
    goals = np.array([[0.3, 0.2], [-0.1, 0.4], [0.0, -0.5]])
    rng = np.random.default_rng(0)
    answers = {goal_key(g): rng.uniform(-1, 1, 7) for g in goals}

    def inverse(goal):
        return answers[goal_key(goal)]

    kept_world = Counting(n_joints=7, noise=0.02, seed=11)
    kept = Evaluator(kept_world, goals)
    first = kept.evaluate(inverse)
    answers[goal_key(goals[1])] = rng.uniform(-1, 1, 7)  # one answer changes
    second = kept.evaluate(inverse)
    assert kept_world.casts == 3 + 1
    fresh = Evaluator(PlanarArm(n_joints=7, noise=0.02, seed=11), goals).evaluate(inverse)
    assert np.array_equal(second.distances, fresh.distances)
    assert second.distances[0] == first.distances[0] and second.distances[2] == first.distances[2]
