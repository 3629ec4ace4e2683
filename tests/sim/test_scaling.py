"""Action and outcome maps: edges land on the documented ranges, both directions invert."""

import numpy as np

from sim_bridge import scaling


def test_joint_edges_and_inverse() -> None:
    lo, hi = scaling.JOINT_RANGES[:, 0], scaling.JOINT_RANGES[:, 1]
    np.testing.assert_allclose(scaling.to_joint(-np.ones(6)), lo)
    np.testing.assert_allclose(scaling.to_joint(np.ones(6)), hi)
    np.testing.assert_allclose(scaling.to_joint(np.zeros(6)), (lo + hi) / 2)
    a = np.random.default_rng(0).uniform(-1, 1, 6)
    np.testing.assert_allclose(scaling.from_joint(scaling.to_joint(a)), a)


def test_duration_edges_and_inverse() -> None:
    np.testing.assert_allclose(scaling.to_duration(-1.0), scaling.DURATION_MIN)
    np.testing.assert_allclose(scaling.to_duration(1.0), scaling.DURATION_MAX)
    np.testing.assert_allclose(scaling.from_duration(scaling.to_duration(0.3)), 0.3)


def test_action_layout_is_four_numbers_per_joint() -> None:
    a = np.zeros(24)
    a[4 * 2 + 0] = 1.0  # joint3 start
    a[4 * 5 + 3] = -1.0  # joint6 duration
    start, middle, end, dur = scaling.action_to_commands(a)
    assert np.isclose(start[2], scaling.JOINT_RANGES[2, 1])
    assert np.isclose(middle[2], np.mean(scaling.JOINT_RANGES[2])) and end[2] == middle[2]
    assert np.isclose(dur[5], scaling.DURATION_MIN)


def test_outcome_box_corners_and_inverse() -> None:
    x0, x1, y0, y1 = scaling.OUTCOME_BOX
    np.testing.assert_allclose(scaling.world_to_outcome([x0, y0]), [-1, -1])
    np.testing.assert_allclose(scaling.world_to_outcome([x1, y1]), [1, 1])
    np.testing.assert_allclose(scaling.outcome_to_world([1, -1]), [x1, y0])
    u = np.array([[0.2, -0.7], [-0.9, 0.4]])
    np.testing.assert_allclose(scaling.world_to_outcome(scaling.outcome_to_world(u)), u)
