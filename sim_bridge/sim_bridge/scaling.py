"""Fixed maps between the normalised spaces the learners see and the robot's physical units.

Why fixed and documented: every learner, benchmark goal and teaching entry is stored in the
normalised units, so these constants define the problem; changing one invalidates the data files
in ``sim_bridge/data`` (regenerate them with the tools in ``sim_bridge.tools``).

Action: 24 numbers in [-1, 1], 4 per joint in joint order (joint1..joint6):
``[start, middle, end, duration]``. A position number ``a`` maps linearly onto the joint's casting
range ``[lo, hi]`` (``-1 -> lo``, ``+1 -> hi``); a duration number maps linearly onto
``[DURATION_MIN, DURATION_MAX]`` seconds.

Outcome: the world point ``(x, y)`` in metres (robot base at the origin, x forward, y to the left)
where the hook lands on water maps linearly onto [-1, 1]^2 through the box ``OUTCOME_BOX``, the
bounding box of the water (``lake.water_bounding_box()``, every part of which the mapping run
reaches, see README_world.md), so no water landing is ever clipped.
"""

from __future__ import annotations

import numpy as np

N_JOINTS = 6
ACTION_DIM = 4 * N_JOINTS
OUTCOME_DIM = 2
# The outcome noise under the paper's protocol (20 random actions x 10 casts; the mean over
# actions of the mean distance of the casts to their mean), averaged over 12 seeds: about 0.07
# (paper 0.073; today's figure: `ros_ws/reproduce.sh world`, sim_bridge/README_world.md). The
# learner's distances are multiples of it.
OUTCOME_NOISE = 0.07

# Casting ranges (rad), inside the xArm6 limits: yaw +-46 deg in front of the pier; shoulder,
# elbow and wrist ranges in which the rod goes from pointing back over the shoulder to pointing
# down at the water; forearm roll for side casts; flange roll spins the rod about its own axis
# (nearly redundant, as a real wrist roll is). Chosen, see README_world.md.
JOINT_RANGES: np.ndarray = np.array(
    [
        [-0.8, 0.8],  # joint1 base yaw
        [-0.9, 0.6],  # joint2 shoulder pitch
        [-2.4, -0.6],  # joint3 elbow pitch
        [-0.8, 0.8],  # joint4 forearm roll
        [-1.6, 0.4],  # joint5 wrist pitch
        [-1.5, 1.5],  # joint6 flange roll
    ]
)
DURATION_MIN = 0.25  # s: the fastest a joint's curve may be run (the motors then lag behind it)
DURATION_MAX = 0.90  # s: slow enough to lay the hook down, short enough to keep casts cheap

# World box (m) mapped onto [-1, 1]^2: x_min, x_max, y_min, y_max. The bounding box of the water
# (lake.py; a test checks they agree); square, so distances scale the same along x and y.
OUTCOME_BOX: np.ndarray = np.array([-8.5, 8.5, -8.5, 8.5])


def split_action(action: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Start, middle, end (normalised) and duration (normalised) arrays of 6 values each."""
    a = np.asarray(action, dtype=float).reshape(N_JOINTS, 4)
    return a[:, 0], a[:, 1], a[:, 2], a[:, 3]


def to_joint(a: np.ndarray, ranges: np.ndarray = JOINT_RANGES) -> np.ndarray:
    """Normalised joint positions (..., 6) -> radians."""
    lo, hi = ranges[:, 0], ranges[:, 1]
    return lo + (np.asarray(a, dtype=float) + 1.0) * 0.5 * (hi - lo)


def from_joint(q: np.ndarray, ranges: np.ndarray = JOINT_RANGES) -> np.ndarray:
    """Radians (..., 6) -> normalised joint positions (inverse of ``to_joint``)."""
    lo, hi = ranges[:, 0], ranges[:, 1]
    return 2.0 * (np.asarray(q, dtype=float) - lo) / (hi - lo) - 1.0


def to_duration(a: np.ndarray) -> np.ndarray:
    """Normalised durations -> seconds."""
    return DURATION_MIN + (np.asarray(a, dtype=float) + 1.0) * 0.5 * (DURATION_MAX - DURATION_MIN)


def from_duration(d: np.ndarray) -> np.ndarray:
    """Seconds -> normalised durations (inverse of ``to_duration``)."""
    return 2.0 * (np.asarray(d, dtype=float) - DURATION_MIN) / (DURATION_MAX - DURATION_MIN) - 1.0


def action_to_commands(action: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Action (24,) -> start, middle, end (rad) and durations (s), 6 values each."""
    s, m, e, d = split_action(action)
    return to_joint(s), to_joint(m), to_joint(e), to_duration(d)


def world_to_outcome(xy: np.ndarray, box: np.ndarray = OUTCOME_BOX) -> np.ndarray:
    """World (x, y) in metres (..., 2) -> normalised outcome (unclipped)."""
    xy = np.asarray(xy, dtype=float)
    lo = np.array([box[0], box[2]])
    hi = np.array([box[1], box[3]])
    return 2.0 * (xy - lo) / (hi - lo) - 1.0


def outcome_to_world(u: np.ndarray, box: np.ndarray = OUTCOME_BOX) -> np.ndarray:
    """Normalised outcome (..., 2) -> world (x, y) in metres (inverse of ``world_to_outcome``)."""
    u = np.asarray(u, dtype=float)
    lo = np.array([box[0], box[2]])
    hi = np.array([box[1], box[3]])
    return lo + (u + 1.0) * 0.5 * (hi - lo)
