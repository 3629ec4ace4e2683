"""Cheap analytic worlds: planar arms with many equal links.

Action in [-1, 1]^n -> joint angles action * max_angle (relative angles, summed along the
chain); outcome = end point divided by the arm's length. With many joints, random actions curl
the arm and their end points pile up where most postures lead, while the rest of the reachable
set is rare: as in the paper's fishing world, motor babbling covers the outcome space badly and
goal babbling helps. Optional Gaussian outcome noise comes from the arm's own seeded Generator.

Each arm declares its ``scale`` (scale.WorldScale): the box goals are drawn in, and the
outcome noise measured the paper's way. Two presets are the benchmark worlds of issue 10
(``ARMS``): a 7-joint arm whose reachable disc fills most of its box, and a 20-joint arm of small
joint range whose reachable crescent covers only about a quarter of its declared box (the
setting where Baranes & Oudeyer 2013 show interest-driven goals beating uniform goals).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .environment import MovementResult, Status
from .scale import WorldScale, gaussian_noise_2d

UNIT_BOX = ((-1.0, -1.0), (1.0, 1.0))
NOISE_FREE_RESOLUTION = 0.005
"""A noise-free arm still declares a noise: 0.5 % of its box side, the precision one can
sensibly ask of a learner (LearnerConfig's distances are multiples of the noise)."""


class PlanarArm:
    """Environment protocol: ``action_dim``, ``outcome_dim``, ``scale`` and ``execute``."""

    def __init__(self, n_joints: int = 12, max_angle: float = np.pi / 3, noise: float = 0.0,
                 seed: int = 0, box: tuple[tuple[float, float], tuple[float, float]] = UNIT_BOX
                 ) -> None:
        if n_joints < 1:
            raise ValueError("n_joints must be >= 1")
        if noise < 0:
            raise ValueError("noise must be >= 0")
        self.action_dim = n_joints
        self.outcome_dim = 2
        self.max_angle = max_angle
        self.noise = noise
        self.box = (tuple(map(float, box[0])), tuple(map(float, box[1])))
        size = max(h - lo for lo, h in zip(*self.box, strict=True))
        declared = gaussian_noise_2d(noise) if noise > 0 else NOISE_FREE_RESOLUTION * size
        self.scale = WorldScale(self.box[0], self.box[1], declared)
        self.rng = np.random.default_rng(seed)

    def forward(self, actions: np.ndarray) -> np.ndarray:
        """Noise-free end points for one action (n,) or a batch (b, n)."""
        a = np.clip(np.asarray(actions, dtype=float), -1.0, 1.0)
        angles = np.cumsum(a * self.max_angle, axis=-1)
        n = a.shape[-1]
        return np.stack([np.cos(angles).sum(-1), np.sin(angles).sum(-1)], axis=-1) / n

    def execute(self, action: np.ndarray) -> MovementResult:
        action = np.asarray(action, dtype=float)
        if action.shape != (self.action_dim,) or not np.all(np.isfinite(action)):
            return MovementResult(None, Status.INVALID_ACTION)
        y = self.forward(action)
        if self.noise > 0:
            y = y + self.rng.normal(0.0, self.noise, size=2)
        return MovementResult(np.clip(y, self.box[0], self.box[1]), Status.OK)


@dataclass(frozen=True)
class ArmSpec:
    """A named analytic benchmark world (bench_learners.py, the runner's --env)."""

    n_joints: int
    max_angle: float
    noise: float
    box: tuple[tuple[float, float], tuple[float, float]]
    cells: tuple[int, int]  # benchmark grid over the box

    def make(self, seed: int, noise: float | None = None) -> PlanarArm:
        return PlanarArm(self.n_joints, self.max_angle, self.noise if noise is None else noise,
                         seed, self.box)


ARMS = {
    # 7 joints of +-60 deg: the reachable disc is about 57 % of [-1, 1]^2.
    "arm-7": ArmSpec(7, np.pi / 3, 0.02, UNIT_BOX, (12, 12)),
    # 20 joints of +-15 deg: a crescent of area ~0.65 in a declared box of 1.5 x 1.8 = 2.7
    # (about 4 times the reachable area); random actions land near the straight arm (x ~ 0.9).
    "arm-20": ArmSpec(20, np.pi / 12, 0.02, ((-0.4, -0.9), (1.1, 0.9)), (14, 14)),
}


@dataclass(frozen=True)
class TeachingSet:
    """Same fields as sim_bridge.data_files.load_teaching_set()'s result."""

    actions: np.ndarray  # (M, n)
    outcomes: np.ndarray  # (M, 2)
    spread: np.ndarray  # (M,) outcome spread under noise (0 for the noise-free arm)


def _pose_pool(arm: PlanarArm, n: int, rng: np.random.Generator) -> np.ndarray:
    """Poses covering the reachable set: random actions scaled by a random factor (from curled
    to straight) plus constant-curvature arcs, since plain random actions miss far outcomes."""
    u = rng.uniform(-1, 1, (n, arm.action_dim)) * rng.uniform(0, 1, (n, 1))
    arcs = rng.uniform(-1, 1, (n // 4, 1)) + rng.uniform(-0.1, 0.1, (n // 4, arm.action_dim))
    return np.clip(np.vstack([u, arcs]), -1, 1)


def grid_cells(outcomes: np.ndarray, cells: int | tuple[int, int],
               box: tuple[tuple[float, float], tuple[float, float]] = UNIT_BOX,
               offset: float = 0.0) -> dict[tuple[int, int], int]:
    """First pool index falling in each cell of a cells grid over ``box``; ``offset`` shifts
    the grid by that fraction of a cell (a second, disjoint-looking set of goals)."""
    n = np.broadcast_to(np.asarray(cells), (2,))
    low, high = np.asarray(box[0], float), np.asarray(box[1], float)
    pos = (outcomes - low) / (high - low) * n + offset
    ij = np.clip(np.floor(pos).astype(int), 0, n - 1)
    first: dict[tuple[int, int], int] = {}
    for idx, (i, j) in enumerate(ij):
        first.setdefault((int(i), int(j)), idx)
    return first


def benchmark_goals(arm: PlanarArm, cells: int | tuple[int, int] = 12, pool: int = 20000,
                    seed: int = 0, offset: float = 0.0) -> np.ndarray:
    """Reachable benchmark goals, one per occupied grid cell of the arm's box (as explauto's
    test set and the paper's benchmark: built from reached points only), sorted by cell.
    Another ``seed`` and ``offset`` give a separate validation set for choosing parameters."""
    rng = np.random.default_rng(seed)
    actions = _pose_pool(arm, pool, rng)
    outcomes = arm.forward(actions)
    first = grid_cells(outcomes, cells, arm.box, offset)
    return outcomes[[first[k] for k in sorted(first)]]


def teaching_set(arm: PlanarArm, n: int = 27, cells: int | tuple[int, int] = 12,
                 pool: int = 20000, seed: int = 1) -> TeachingSet:
    """n demonstrations spread over the reachable set (27 as in the paper), drawn from the
    occupied grid cells with a seeded Generator."""
    rng = np.random.default_rng(seed)
    actions = _pose_pool(arm, pool, rng)
    outcomes = arm.forward(actions)
    keys = sorted(grid_cells(outcomes, cells, arm.box).items())
    pick = rng.choice(len(keys), size=min(n, len(keys)), replace=False)
    idx = np.array([keys[p][1] for p in sorted(pick)])
    return TeachingSet(actions[idx], outcomes[idx], np.zeros(len(idx)))
