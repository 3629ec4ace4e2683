"""Joint trajectories of a cast: one quadratic Bezier curve per joint.

Why a quadratic Bezier with the *middle* position as its control point: the paper's action gives a
start, a middle and an end position per joint, and a curve that stays inside the convex hull of
its three points can never leave the joint's range, so no clipping distorts the action.

The curve, for a joint with start ``p0``, middle (control point) ``p1``, end ``p2`` and duration
``T``, is run with the smoothstep time parametrisation ``tau = clip(t / T, 0, 1)``,
``s = 3 tau^2 - 2 tau^3``::

    q(t)  = (1 - s)^2 p0 + 2 s (1 - s) p1 + s^2 p2
    dq/dt = (2 (1 - s) (p1 - p0) + 2 s (p2 - p1)) * 6 tau (1 - tau) / T

so ``q(0) = p0``, ``q(T/2) = (p0 + 2 p1 + p2) / 4`` (``s = 1/2`` at ``tau = 1/2``), ``q(T) = p2``,
and the joint holds ``p2`` after ``T``. The curve passes through ``p1`` only when ``p1`` is the
mean of ``p0`` and ``p2``. Why smoothstep rather than ``s = t / T``: the velocity is zero at both
ends, so the servos never get a velocity step; a linear ``s`` stops a joint dead at ``T``, which
whipped the light line so hard that pybullet's explicit step exploded on 4 % of random casts.
"""

from __future__ import annotations

import numpy as np


def bezier_position(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Quadratic Bezier at curve parameter ``s`` in [0, 1] (broadcasts)."""
    u = 1.0 - s
    return u * u * p0 + 2.0 * s * u * p1 + s * s * p2


def bezier_derivative(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray, s: np.ndarray) -> np.ndarray:
    """d/ds of the quadratic Bezier (divide by the duration to get a joint velocity)."""
    return 2.0 * (1.0 - s) * (p1 - p0) + 2.0 * s * (p2 - p1)


def joint_trajectory(
    start: np.ndarray,
    middle: np.ndarray,
    end: np.ndarray,
    duration: np.ndarray,
    times: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities, shape (len(times), n_joints), of every joint at every time.

    Each joint j runs its own curve over its own ``duration[j]`` and holds its end afterwards.
    """
    start, middle, end, duration = (
        np.asarray(v, dtype=float) for v in (start, middle, end, duration)
    )
    if np.any(duration <= 0.0):
        raise ValueError("durations must be positive")
    t = np.asarray(times, dtype=float)[:, None]
    tau = np.clip(t / duration[None, :], 0.0, 1.0)
    s = smoothstep(tau)
    q = bezier_position(start, middle, end, s)
    dq = bezier_derivative(start, middle, end, s) * (6.0 * tau * (1.0 - tau)) / duration[None, :]
    return q, dq


def smoothstep(tau: np.ndarray) -> np.ndarray:
    """Curve parameter at normalised time ``tau`` in [0, 1]: zero slope at both ends."""
    return tau * tau * (3.0 - 2.0 * tau)
