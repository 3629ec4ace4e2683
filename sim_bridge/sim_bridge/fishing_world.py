"""The fishing-rod world: an xArm6 casts a flexible rod in pybullet; the hook's landing point.

Why this design (details and measured figures in ``sim_bridge/README_world.md``):
- The arm follows one quadratic Bezier per joint (``bezier.py``) with force- and speed-limited
  position motors; the rod bends at passive joints driven by explicit spring-damper torques; the
  line is two light links on free spherical joints; the hook is a small mass at its end.
- The cast is a real cast: the reel is opened when the arm's motion ends (the longest joint
  duration), and from then on the hook flies free under gravity and linear air drag, solved in
  closed form. A long line swinging for seconds is chaotic (see the rod notes); a free flight is
  not, so the landing point depends smoothly on the state at release.
- Water contact is the first downward crossing of the water height by the hook, interpolated
  linearly inside the step (attached phase) or solved exactly (free flight): cheaper and more
  precise than contact detection, so the model has no collision shapes at all.
- The hook must land on water: the water is a reservoir with a shoreline (``lake.py``: a main
  basin with four arms, and a small pond cut off by land; ``FishingWorld(lake=Lake(pond_radius=
  ...))`` makes the pond smaller, ``docs/isolated_region.md``). A hook whose first touch-down is
  on land gives status NO_CONTACT with the message "landed on land at (x, y)", never an outcome.
- Noise is added to the motor commands (Bezier points and durations), drawn from the world's own
  generator: the same seed and the same sequence of actions give bit-identical outcomes.
"""

from __future__ import annotations

import contextlib
import ctypes
import gc
import math
import os
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
import pybullet as pb

from sim_bridge import lake as lake_mod
from sim_bridge import scaling
from sim_bridge.bezier import joint_trajectory
from sim_bridge.rod_urdf import XARM6_JOINTS, RodSpec, build_urdf


class Status(IntEnum):
    """Result codes of a cast (also used by the ROS service)."""

    OK = 0
    NO_CONTACT = 1
    PHYSICS_FAILURE = 2
    INVALID_ACTION = 3


@dataclass(frozen=True)
class CastResult:
    """What one cast produced; ``outcome`` is None unless ``status`` is OK."""

    status: int
    outcome: np.ndarray | None = None  # normalised (x, y) in [-1, 1]^2
    # (x, y) in metres where the hook touched down: on water (status OK) or on land (NO_CONTACT)
    world_point: np.ndarray | None = None
    # the same point in normalised units, unclipped: on land it is not an outcome (nothing to
    # learn from), but it still says how far from a goal the hook came down (evaluation)
    touchdown: np.ndarray | None = None
    clipped: bool = False  # the world point lay outside scaling.OUTCOME_BOX
    touch_time: float = math.nan  # s from the start of the motion to the first water touch
    release_time: float = math.nan  # s, when the reel opened (inf if the hook touched first)
    message: str = ""


# Chosen physical constants (why: README_world.md).
WATER_Z = -2.0  # m: water surface below the robot base (the robot stands on a pier)
GRAVITY = 9.81
AIR_DRAG = 1.5  # 1/s: linear drag rate of the flying hook and float (terminal speed 6.5 m/s)
TIME_LIMIT = 4.0  # s: a hook not in the water by then is NO_CONTACT
MOTOR_TAU = 0.04  # s: time constant of the joint position servo (positionGain = dt / tau)
ROD_STIFFNESS = (40.0, 15.0)  # N m / rad per bend axis, butt and tip bends
ROD_FRICTION = (0.05, 0.02)  # N m: internal friction of the blank, an implicit (stable) damper
PASSIVE_MAX_VELOCITY = 1000.0  # rad/s: lifts pybullet's 100 rad/s clamp off the rod and line
# rad std on every Bezier point and relative std on every duration; tuned so that the paper's
# protocol, averaged over 12 seeds of its 20 actions, measures about 0.07 (the paper: 0.073).
DEFAULT_NOISE = 0.0042
DEFAULT_TIME_STEP = 1.0 / 240.0
MAX_SPEED = 200.0  # m/s: a hook faster than this means the integration exploded
# The constraint solver of the servos and the rod's friction (about 10 rows per step): pybullet's
# MLCP solved directly by Dantzig's pivoting (``_build`` selects it; why: README_world.md). Bullet
# falls back to its sequential-impulse sweeps only if pivoting fails; SOLVER_ITERATIONS is their
# number (and the sweeps of the previous solver, MLCP with projected Gauss-Seidel, which
# bench_sim_speed.py still offers as ``--solver gauss-seidel``).
SOLVER_ITERATIONS = 50


@contextlib.contextmanager
def _quiet_c_stdout() -> Iterator[None]:
    """Silence what C code writes to the process's stdout (file descriptor 1) meanwhile."""
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError):  # no usable stdout: nothing to silence
        yield
        return
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 1)
            try:
                yield
            finally:
                ctypes.CDLL(None).fflush(None)  # C's buffered output goes to /dev/null too
                os.dup2(saved, 1)
    finally:
        os.close(saved)


def validate_action(action: object) -> tuple[np.ndarray | None, str]:
    """The action as a float array, or None and the reason it is refused."""
    try:
        a = np.asarray(action, dtype=float)
    except (TypeError, ValueError):
        return None, "action is not numeric"
    if a.ndim != 1 or a.size != scaling.ACTION_DIM:
        return None, f"action must have {scaling.ACTION_DIM} numbers, got shape {a.shape}"
    if not np.all(np.isfinite(a)):
        return None, "action has NaN or infinite numbers"
    if np.any(np.abs(a) > 1.0):
        return None, "action numbers must lie in [-1, 1]"
    return a, ""


def free_flight_touch(pos: np.ndarray, vel: np.ndarray, water_z: float, drag: float,
                      gravity: float, t_max: float) -> tuple[float, np.ndarray] | None:
    """Time and (x, y) where a point under gravity and linear drag first reaches ``water_z``.

    Closed form: with ``e(t) = (1 - exp(-k t)) / k``, ``x(t) = x0 + vx0 e(t)`` and
    ``z(t) = z0 + (vz0 + g / k) e(t) - g t / k``. ``z`` has at most one maximum, so after the apex
    it falls monotonically: bisection on the falling part finds the unique crossing.
    """
    k, g = drag, gravity
    z0, vz0 = float(pos[2]), float(vel[2])

    def z_at(t: float) -> float:
        return z0 + (vz0 + g / k) * (-math.expm1(-k * t)) / k - g * t / k

    if z0 <= water_z:
        return 0.0, np.array(pos[:2], dtype=float)
    # Apex: vz(t) = (vz0 + g/k) exp(-k t) - g/k = 0.
    t_apex = math.log1p(k * vz0 / g) / k if vz0 > 0.0 else 0.0
    lo, hi = t_apex, max(t_apex, 1e-3)
    while z_at(hi) > water_z:
        lo, hi = hi, 2.0 * hi
        if hi > 2.0 * t_max:
            return None
    for _ in range(60):  # 2^-60 of the bracket: far below float resolution
        mid = 0.5 * (lo + hi)
        if z_at(mid) > water_z:
            lo = mid
        else:
            hi = mid
    t = hi
    e = -math.expm1(-k * t) / k
    return t, np.array([pos[0] + vel[0] * e, pos[1] + vel[1] * e])


class FishingWorld:
    """A pybullet DIRECT world that executes casts; one instance owns one physics client."""

    action_dim = scaling.ACTION_DIM
    outcome_dim = scaling.OUTCOME_DIM

    def __init__(self, seed: int = 0, noise: float = DEFAULT_NOISE,
                 time_step: float = DEFAULT_TIME_STEP, rod: RodSpec | None = None,
                 lake: lake_mod.Lake | None = None) -> None:
        if noise < 0.0 or not math.isfinite(noise):
            raise ValueError("noise must be a finite number >= 0")
        if not 0.0 < time_step <= 0.01:
            raise ValueError("time_step must be in (0, 0.01] s: coarser steps are inaccurate")
        self.noise = float(noise)
        self.time_step = float(time_step)
        # The water's shapes; the default keeps the documented world (README_world.md). Only
        # the test "water or land" depends on it, never the physics.
        self.lake = lake if lake is not None else lake_mod.DEFAULT_LAKE
        self.reseed(seed)
        self._client = pb.connect(pb.DIRECT)
        self._build(rod or RodSpec())

    # -- construction ---------------------------------------------------------------------------
    def _build(self, rod: RodSpec) -> None:
        c = self._client
        pb.setGravity(0.0, 0.0, -GRAVITY, physicsClientId=c)
        pb.setPhysicsEngineParameter(fixedTimeStep=self.time_step, numSubSteps=0,
                                     physicsClientId=c)
        # Dantzig's pivoting solves the step's MLCP exactly. Measured against the converged
        # solver (MLCP, 300 Gauss-Seidel sweeps): touch-downs within 1e-11, where the previous
        # 50 Gauss-Seidel sweeps were up to 0.0028 off; the learnability figures of the time
        # (benchmarks/measure_world.py, now the `world` experiment) identical to the last
        # printed digit; 13-15 % more casts per second (104.8 against 92.8 casts/s,
        # 2026-12-04, AMD EPYC; README_world.md, Constraint solver and Speed).
        with _quiet_c_stdout():  # pybullet prints "switched solver" from C
            pb.setPhysicsEngineParameter(constraintSolverType=pb.CONSTRAINT_SOLVER_LCP_DANTZIG,
                                         numSolverIterations=SOLVER_ITERATIONS,
                                         physicsClientId=c)
        fd, path = tempfile.mkstemp(suffix=".urdf", prefix="fishing_rod_")
        try:
            with os.fdopen(fd, "w") as f:
                f.write(build_urdf(rod))
            # Without this flag pybullet ignores the URDF inertias (it derives them from collision
            # shapes, and this model has none).
            self.body = pb.loadURDF(path, useFixedBase=True,
                                    flags=pb.URDF_USE_INERTIA_FROM_FILE, physicsClientId=c)
        finally:
            os.unlink(path)
        names = [pb.getJointInfo(self.body, j, physicsClientId=c)[1].decode()
                 for j in range(pb.getNumJoints(self.body, physicsClientId=c))]
        self.arm_joints = [names.index(j[0]) for j in XARM6_JOINTS]
        self.rod_joints = [j for j, n in enumerate(names) if n.startswith("rod_bend")]
        self.line_joints = [j for j, n in enumerate(names) if n.startswith("line_joint")]
        self.rod_tip_link = self.rod_joints[-1]
        self.hook_link = names.index("hook_mount")
        self.joint_limits = np.array([[j[4], j[5]] for j in XARM6_JOINTS])
        self.efforts = [j[6] for j in XARM6_JOINTS]
        self.max_velocities = [j[7] for j in XARM6_JOINTS]
        # maxJointVelocity acts on the whole body whatever link is named: lift it for the rod and
        # line; the arm's speed limit is its servos' maxVelocity instead.
        pb.changeDynamics(self.body, -1, maxJointVelocity=PASSIVE_MAX_VELOCITY,
                          physicsClientId=c)
        # Free the passive joints of their default motors (pitfall 1 of the rod notes).
        n_bends = len(self.rod_joints) // 2
        for i, j in enumerate(self.rod_joints):
            pb.setJointMotorControl2(self.body, j, pb.VELOCITY_CONTROL, targetVelocity=0.0,
                                     force=ROD_FRICTION[i // 2], physicsClientId=c)
        for j in self.line_joints:
            pb.setJointMotorControlMultiDof(
                self.body, j, pb.POSITION_CONTROL, targetPosition=[0, 0, 0, 1],
                targetVelocity=[0, 0, 0], positionGain=0, velocityGain=0, force=[0, 0, 0],
                physicsClientId=c)
        self._k = [ROD_STIFFNESS[i // 2] for i in range(2 * n_bends)]
        self._state = pb.saveState(physicsClientId=c)
        # The water is the plane z = WATER_Z, tested against the hook: no body, no collision.
        # Rotation that points the line straight down (used to hang it at rest before a cast).
        self._rest_down = pb.getQuaternionFromEuler([math.pi, 0.0, 0.0])

    def reseed(self, seed: int) -> None:
        """Restart the noise stream as if the world had been built with ``seed``.

        Why: a tool that needs independent noise per item (the floor's goals, the teaching
        set's cells) reseeds one world instead of building one per item (a URDF load each), and
        any single item can then be recomputed alone.
        """
        self.seed = int(seed)
        self.rng = np.random.Generator(np.random.PCG64(self.seed))

    def close(self) -> None:
        """Disconnect the physics client (idempotent)."""
        if self._client is not None and pb.isConnected(self._client):
            pb.disconnect(self._client)
        self._client = None

    def __enter__(self) -> FishingWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- casting --------------------------------------------------------------------------------
    def noisy_commands(self, action: np.ndarray) -> tuple[np.ndarray, ...]:
        """Motor commands of a valid action, with this cast's noise (always 24 draws)."""
        start, middle, end, dur = scaling.action_to_commands(action)
        eps = self.rng.standard_normal(scaling.ACTION_DIM).reshape(scaling.N_JOINTS, 4)
        lo, hi = self.joint_limits[:, 0], self.joint_limits[:, 1]
        start = np.clip(start + self.noise * eps[:, 0], lo, hi)
        middle = np.clip(middle + self.noise * eps[:, 1], lo, hi)
        end = np.clip(end + self.noise * eps[:, 2], lo, hi)
        dur = np.maximum(dur * (1.0 + self.noise * eps[:, 3]), 0.05)
        return start, middle, end, dur

    def _reset_pose(self, q0: np.ndarray) -> None:
        """Arm at the start posture, rod straight, line hanging straight down, all at rest.

        Also arms the servos' speed limit: ``maxVelocity`` (the motor's rhs clamp) is kept by the
        motor until changed, and only the single-joint call sets it, so it is set here once per
        cast and the per-step array call (which cannot set it) keeps it: one call per step
        instead of six, bit-identical (a test compares with the per-joint calls).
        """
        c, b = self._client, self.body
        pb.restoreState(self._state, physicsClientId=c)
        kp = self.time_step / MOTOR_TAU
        for j, q, force, vmax in zip(self.arm_joints, q0, self.efforts, self.max_velocities,
                                     strict=True):
            pb.resetJointState(b, j, float(q), 0.0, physicsClientId=c)
            pb.setJointMotorControl2(b, j, pb.POSITION_CONTROL, targetPosition=float(q),
                                     targetVelocity=0.0, force=force, positionGain=kp,
                                     velocityGain=1.0, maxVelocity=vmax, physicsClientId=c)
        tip = pb.getLinkState(b, self.rod_tip_link, computeForwardKinematics=1,
                              physicsClientId=c)
        tip_orn_inv = pb.invertTransform([0, 0, 0], tip[5])[1]
        rel = pb.multiplyTransforms([0, 0, 0], tip_orn_inv, [0, 0, 0], self._rest_down)[1]
        pb.resetJointStateMultiDof(b, self.line_joints[0], rel, [0, 0, 0], physicsClientId=c)

    def execute(self, action: np.ndarray) -> CastResult:
        """Run one cast; never raises on a bad action (status INVALID_ACTION instead)."""
        a, why = validate_action(action)
        if a is None:
            return CastResult(status=Status.INVALID_ACTION, message=why)
        start, middle, end, dur = self.noisy_commands(a)
        # pybullet returns fresh tuples at every step, which keep triggering Python's cycle
        # collector although a cast makes no cycles: paused for the cast (5 % of its time).
        collecting = gc.isenabled()
        gc.disable()
        try:
            return self._simulate(start, middle, end, dur)
        finally:
            if collecting:
                gc.enable()

    def _simulate(self, start: np.ndarray, middle: np.ndarray, end: np.ndarray,
                  dur: np.ndarray) -> CastResult:
        c, b, dt = self._client, self.body, self.time_step
        self._reset_pose(start)
        n_steps = math.ceil(float(dur.max()) / dt - 1e-9)
        times = np.arange(1, n_steps + 1) * dt  # target at the end of each step
        q_ref, dq_ref = joint_trajectory(start, middle, end, dur, times)
        q_ref, dq_ref = q_ref.tolist(), dq_ref.tolist()
        arm, rod, hook, k = self.arm_joints, self.rod_joints, self.hook_link, self._k
        kp = self.time_step / MOTOR_TAU
        efforts, gains_p, gains_v = list(self.efforts), [kp] * len(arm), [1.0] * len(arm)
        z_prev = pb.getLinkState(b, hook, 0, 0, c)[4]
        if z_prev[2] <= WATER_Z:
            return CastResult(status=Status.PHYSICS_FAILURE, message="hook starts under water")
        # Per step: 5 pybullet calls (positional arguments: no keyword parsing), all the work.
        set_motors, get_states, step, get_link = (pb.setJointMotorControlArray,
                                                  pb.getJointStates, pb.stepSimulation,
                                                  pb.getLinkState)
        position, torque = pb.POSITION_CONTROL, pb.TORQUE_CONTROL
        for i in range(n_steps):
            set_motors(b, arm, position, q_ref[i], dq_ref[i], efforts, gains_p, gains_v, c)
            states = get_states(b, rod, c)
            tau = [-ki * s[0] for ki, s in zip(k, states, strict=True)]
            set_motors(b, rod, torque, forces=tau, physicsClientId=c)
            step(c)
            p = get_link(b, hook, 0, 0, c)[4]
            if not abs(p[2]) < 1e3:
                return CastResult(status=Status.PHYSICS_FAILURE, message="state exploded")
            if p[2] <= WATER_Z:
                f = (z_prev[2] - WATER_Z) / (z_prev[2] - p[2])
                xy = np.array([z_prev[0] + f * (p[0] - z_prev[0]),
                               z_prev[1] + f * (p[1] - z_prev[1])])
                return self._landed(xy, (i + f) * dt, math.inf)
            z_prev = p
        # Release: the hook flies free from its current position and velocity.
        ls = get_link(b, hook, computeLinkVelocity=1, physicsClientId=c)
        pos, vel = np.array(ls[4]), np.array(ls[6])
        t_rel = n_steps * dt
        if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(vel))
                and math.sqrt(float((vel * vel).sum())) < MAX_SPEED):
            return CastResult(status=Status.PHYSICS_FAILURE, message="state exploded at release")
        hit = free_flight_touch(pos, vel, WATER_Z, AIR_DRAG, GRAVITY, TIME_LIMIT - t_rel)
        if hit is None or t_rel + hit[0] > TIME_LIMIT:
            return CastResult(status=Status.NO_CONTACT, release_time=t_rel,
                              message="the hook did not reach the water within the time limit")
        return self._landed(hit[1], t_rel + hit[0], t_rel)

    def _landed(self, xy: np.ndarray, t_touch: float, t_rel: float) -> CastResult:
        u = scaling.world_to_outcome(xy)
        if self.lake.body_at(float(xy[0]), float(xy[1])) == lake_mod.LAND:
            return CastResult(status=Status.NO_CONTACT, world_point=xy, touchdown=u,
                              touch_time=t_touch,
                              release_time=t_rel,
                              message=f"landed on land at ({xy[0]:.3f}, {xy[1]:.3f})")
        clipped = bool(np.any(np.abs(u) > 1.0))
        return CastResult(status=Status.OK, outcome=np.clip(u, -1.0, 1.0), world_point=xy,
                          touchdown=u,
                          clipped=clipped, touch_time=t_touch, release_time=t_rel)
