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

from collections import deque
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from . import portable
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
        self.reseed(seed)

    def reseed(self, seed: int) -> None:
        """Restart the noise stream as if the arm had been built with ``seed``
        (repeatable_casts.py gives each evaluation goal its own)."""
        self.seed = int(seed)
        self.rng = np.random.default_rng(self.seed)

    def forward(self, actions: np.ndarray) -> np.ndarray:
        """Noise-free end points for one action (n,) or a batch (b, n)."""
        a = np.clip(np.asarray(actions, dtype=float), -1.0, 1.0)
        angles = np.cumsum(a * self.max_angle, axis=-1)
        n = a.shape[-1]
        return np.stack([portable.cos(angles).sum(-1), portable.sin(angles).sum(-1)],
                        axis=-1) / n

    def jacobian(self, action: np.ndarray) -> np.ndarray:
        """d forward / d action at one action (2, n): joint k turns every link from k on."""
        a = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        angles = np.cumsum(a * self.max_angle)
        tail = lambda v: np.cumsum(v[::-1])[::-1]  # noqa: E731  sum over links j >= k
        scale = self.max_angle / len(a)
        return np.stack([-tail(portable.sin(angles)), tail(portable.cos(angles))]) * scale

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
    # 20 joints of +-9 deg (curled at most into a half circle): the reachable set is about a
    # quarter of the declared box of 1.5 x 1.8 (reachable_cells); random actions land near the
    # straight arm (x ~ 0.96).
    "arm-20": ArmSpec(20, np.pi / 20, 0.02, ((-0.4, -0.9), (1.1, 0.9)), (16, 16)),
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


SOLVED = 1e-6
"""A point counts as reachable when least squares on the noise-free arm lands this close."""


MAX_STEPS = 100
"""Gauss-Newton steps per start of ``solve``: a reachable goal is met in a handful."""


def solve(arm: PlanarArm, goal: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, float]:
    """The best action found for ``goal`` from each start, and its noise-free distance to
    the goal: Gauss-Newton's smallest step to the goal (the arm is redundant), halved until it
    gets closer, kept in the action box. Computed with core/portable.py, so the arms' goals
    and teaching sets are the same on every CPU (scipy's least squares rounded by CPU)."""
    goal = np.asarray(goal, dtype=float)
    best, best_err = np.clip(np.asarray(starts[0], float), -1.0, 1.0), np.inf
    for x0 in starts:
        x = np.clip(np.asarray(x0, dtype=float), -1.0, 1.0)
        err = portable.norm(arm.forward(x) - goal)
        for _ in range(MAX_STEPS):
            if err < 0.1 * SOLVED:
                break
            delta = _bounded_step(arm.jacobian(x), goal - arm.forward(x), x)
            length = 1.0
            while length > 1e-6:
                trial = np.clip(x + length * delta, -1.0, 1.0)
                trial_err = portable.norm(arm.forward(trial) - goal)
                if trial_err < err:
                    x, err = trial, trial_err
                    break
                length *= 0.5
            else:
                break  # no step gets closer: a local minimum or the box's edge
        if err < best_err:
            best, best_err = x, err
        if best_err < SOLVED:
            break
    return best, best_err


def _bounded_step(jac: np.ndarray, gap: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Gauss-Newton's smallest step towards ``gap`` that moves no joint held at a bound of
    the box further out: such joints are dropped from the step until none is left that the
    step would push out (an active set)."""
    free = np.ones(len(x), dtype=bool)
    delta = np.zeros(len(x))
    for _ in range(len(x)):
        if free.sum() < len(gap):
            break
        delta = np.zeros(len(x))
        delta[free] = portable.minimum_norm_step(jac[:, free], gap)
        out = free & (((x >= 1.0) & (delta > 0.0)) | ((x <= -1.0) & (delta < 0.0)))
        if not out.any():
            break
        free &= ~out
    return delta


@dataclass(frozen=True)
class ReachableCells:
    """For each cell of a grid over the arm's box: a witness posture landing in it, or none.

    Random postures (even the varied ones of _pose_pool) miss most of a long arm's reachable
    set, so the map grows from them: every unreached cell next to a reached one is tried by
    least squares from its neighbours' postures, towards a seeded random point of the cell,
    until no new cell is reached (a flood fill over the reachable set)."""

    cells: tuple[int, int]
    actions: np.ndarray  # (cx, cy, n) witness posture, NaN rows where unreached
    outcomes: np.ndarray  # (cx, cy, 2) its noise-free outcome (inside the cell)

    @property
    def reached(self) -> np.ndarray:
        return ~np.isnan(self.outcomes[..., 0])

    def reached_points(self) -> tuple[np.ndarray, np.ndarray]:
        """(actions, outcomes) of the reached cells, in cell order."""
        mask = self.reached
        return self.actions[mask], self.outcomes[mask]


def reachable_cells(arm: PlanarArm, cells: int | tuple[int, int], seed: int = 0,
                    pool: int = 20000) -> ReachableCells:
    """The flood fill of ReachableCells over ``cells`` of the arm's box (deterministic)."""
    n = tuple(int(c) for c in np.broadcast_to(np.asarray(cells), (2,)))
    low, high = np.asarray(arm.box[0], float), np.asarray(arm.box[1], float)
    width = (high - low) / n
    rng = np.random.default_rng(seed)
    poses = _pose_pool(arm, pool, rng)
    actions = np.full((*n, arm.action_dim), np.nan)
    outcomes = np.full((*n, 2), np.nan)
    for (i, j), k in grid_cells(arm.forward(poses), n, arm.box).items():
        actions[i, j], outcomes[i, j] = poses[k], arm.forward(poses[k])
    tried = np.zeros(n, bool)
    neighbours = [(-1, 0), (1, 0), (0, -1), (0, 1)]
    queue = deque(sorted(zip(*np.nonzero(~np.isnan(outcomes[..., 0])), strict=True)))
    while queue:
        ci, cj = queue.popleft()
        for di, dj in neighbours:
            i, j = int(ci) + di, int(cj) + dj
            if not (0 <= i < n[0] and 0 <= j < n[1]) or tried[i, j] or not np.isnan(
                    outcomes[i, j, 0]):
                continue
            tried[i, j] = True
            target = low + (np.array([i, j]) + rng.uniform(0.05, 0.95, 2)) * width
            starts = [actions[i + a, j + b] for a, b in neighbours
                      if 0 <= i + a < n[0] and 0 <= j + b < n[1]
                      and not np.isnan(actions[i + a, j + b, 0])]
            action, err = solve(arm, target, np.array(starts))
            if err < SOLVED:
                actions[i, j], outcomes[i, j] = action, arm.forward(action)
                queue.append((i, j))
    return ReachableCells(n, actions, outcomes)


@lru_cache(maxsize=8)
def _cached_reach(n_joints: int, max_angle: float, box: tuple, cells: tuple[int, int],
                  seed: int) -> ReachableCells:
    return reachable_cells(PlanarArm(n_joints, max_angle, 0.0, 0, box), cells, seed)


def reach_of(arm: PlanarArm, cells: int | tuple[int, int], seed: int = 0) -> ReachableCells:
    """reachable_cells, computed once per arm geometry and grid in a process."""
    n = tuple(int(c) for c in np.broadcast_to(np.asarray(cells), (2,)))
    return _cached_reach(arm.action_dim, float(arm.max_angle), arm.box, n, seed)


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


def benchmark_goals(arm: PlanarArm, cells: int | tuple[int, int] = 12, seed: int = 0
                    ) -> np.ndarray:
    """Reachable benchmark goals, one per reachable cell of a grid over the arm's box (the
    paper's benchmark: built from reached points only), in cell order. Another ``seed`` draws
    other points in the same cells: a separate validation set for choosing parameters."""
    return reach_of(arm, cells, seed).reached_points()[1]


def teaching_set(arm: PlanarArm, n: int = 27, cells: int | tuple[int, int] = 12,
                 seed: int = 1) -> TeachingSet:
    """n demonstrations spread over the reachable set (27 as in the paper): postures of
    distinct reachable cells, drawn with a seeded Generator."""
    actions, outcomes = reach_of(arm, cells, seed).reached_points()
    rng = np.random.default_rng(seed)
    idx = np.sort(rng.choice(len(outcomes), size=min(n, len(outcomes)), replace=False))
    return TeachingSet(actions[idx], outcomes[idx], np.zeros(len(idx)))
