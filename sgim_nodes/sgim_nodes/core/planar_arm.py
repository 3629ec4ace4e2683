"""A cheap analytic world: a planar arm with many equal links.

Action in [-1, 1]^n -> joint angles action * max_angle (relative angles, summed along the
chain); outcome = end point divided by the arm's length, so it lies in the unit disc inside
[-1, 1]^2.  With many joints, random actions curl the arm and their end points pile up near
the base while stretched poses (far outcomes) are rare: like the paper's fishing world, motor
babbling covers the outcome space badly and goal babbling helps.  Optional Gaussian outcome
noise comes from the arm's own seeded Generator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .environment import MovementResult, Status


class PlanarArm:
    """Environment protocol: ``action_dim``, ``outcome_dim`` and ``execute``."""

    def __init__(self, n_joints: int = 12, max_angle: float = np.pi / 3, noise: float = 0.0,
                 seed: int = 0) -> None:
        if n_joints < 1:
            raise ValueError("n_joints must be >= 1")
        self.action_dim = n_joints
        self.outcome_dim = 2
        self.max_angle = max_angle
        self.noise = noise
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
        return MovementResult(np.clip(y, -1.0, 1.0), Status.OK)


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


def grid_cells(outcomes: np.ndarray, cells: int) -> dict[tuple[int, int], int]:
    """First pool index falling in each cell of a cells x cells grid over [-1, 1]^2."""
    ij = np.clip(((outcomes + 1.0) / 2.0 * cells).astype(int), 0, cells - 1)
    first: dict[tuple[int, int], int] = {}
    for idx, (i, j) in enumerate(ij):
        first.setdefault((int(i), int(j)), idx)
    return first


def benchmark_goals(arm: PlanarArm, cells: int = 12, pool: int = 20000, seed: int = 0
                    ) -> np.ndarray:
    """Reachable benchmark goals, one per grid cell (as explauto's test set), sorted."""
    rng = np.random.default_rng(seed)
    actions = _pose_pool(arm, pool, rng)
    outcomes = arm.forward(actions)
    first = grid_cells(outcomes, cells)
    return outcomes[[first[k] for k in sorted(first)]]


def teaching_set(arm: PlanarArm, n: int = 27, cells: int = 12, pool: int = 20000,
                 seed: int = 1) -> TeachingSet:
    """n demonstrations spread over the reachable set (27 as in the paper), drawn from the
    occupied grid cells with a seeded Generator."""
    rng = np.random.default_rng(seed)
    actions = _pose_pool(arm, pool, rng)
    outcomes = arm.forward(actions)
    keys = sorted(grid_cells(outcomes, cells).items())
    pick = rng.choice(len(keys), size=min(n, len(keys)), replace=False)
    idx = np.array([keys[p][1] for p in sorted(pick)])
    return TeachingSet(actions[idx], outcomes[idx], np.zeros(len(idx)))
