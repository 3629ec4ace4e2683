"""Bezier joint trajectories: values at known points, zero end velocities, hold after the end."""

import numpy as np

from sim_bridge.bezier import bezier_position, joint_trajectory, smoothstep


def test_quadratic_bezier_known_points() -> None:
    p0, p1, p2 = np.array([0.0]), np.array([1.0]), np.array([4.0])
    assert bezier_position(p0, p1, p2, np.array(0.0)) == 0.0
    assert bezier_position(p0, p1, p2, np.array(1.0)) == 4.0
    # (p0 + 2 p1 + p2) / 4 at s = 1/2: the middle is a control point, not a via point.
    assert bezier_position(p0, p1, p2, np.array(0.5)) == 1.5


def test_trajectory_times_ends_and_hold() -> None:
    start, middle, end = np.array([0.0, -1.0]), np.array([2.0, 0.0]), np.array([1.0, 1.0])
    dur = np.array([0.5, 1.0])
    t = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 2.0])
    q, dq = joint_trajectory(start, middle, end, dur, t)
    np.testing.assert_allclose(q[0], start)
    np.testing.assert_allclose(q[1, 0], (0.0 + 2 * 2.0 + 1.0) / 4)  # joint 0 at T/2
    np.testing.assert_allclose(q[2:, 0], 1.0)  # joint 0 holds its end after 0.5 s
    np.testing.assert_allclose(q[4:, 1], 1.0)
    np.testing.assert_allclose(dq[0], 0.0)  # smoothstep: no velocity step at the start
    np.testing.assert_allclose(dq[-1], 0.0)
    assert dq[1, 0] > 0.0


def test_velocity_is_derivative_of_position() -> None:
    start, middle, end, dur = np.array([0.3]), np.array([-1.2]), np.array([0.9]), np.array([0.7])
    t = np.linspace(0.01, 0.69, 30)
    h = 1e-6
    q_plus, _ = joint_trajectory(start, middle, end, dur, t + h)
    q_minus, _ = joint_trajectory(start, middle, end, dur, t - h)
    _, dq = joint_trajectory(start, middle, end, dur, t)
    np.testing.assert_allclose(dq, (q_plus - q_minus) / (2 * h), rtol=1e-5, atol=1e-6)


def test_smoothstep_ends() -> None:
    np.testing.assert_allclose(smoothstep(np.array([0.0, 0.5, 1.0])), [0.0, 0.5, 1.0])
