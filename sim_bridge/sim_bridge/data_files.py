"""Load the world's data files: reachable map, benchmark goals, teaching set and floor.

Why a search path: in the source tree the files sit in ``sim_bridge/data`` next to the package;
installed by colcon they sit in ``<prefix>/share/sim_bridge/data`` (setup.py ``data_files``), and
installed as package data in ``sim_bridge/data`` inside the package. Every candidate is a path
relative to this module (or ``SIM_BRIDGE_DATA_DIR``), so no ROS import and no working directory
is needed.

The isolated region (the pond cut off by land, ``lake.py``) is re-exported here so the analysis can
measure each learner's coverage of it: ``ISOLATED_REGION = {"centre": (-0.85, -0.25), "radius":
0.088}`` in normalised outcome units, and ``in_isolated_region(outcomes)``. For a world with
another pond (``lake.Lake(pond_radius=...)``), ``isolated_region(lake)`` and
``lake.in_isolated_region(outcomes)``; ``load_reachable_casts(..., lake=lake)`` keeps only the
mapped casts that land on that lake's water (a smaller pond's landings are a subset of the
default pond's, the physics being the same).
"""

from __future__ import annotations

import os
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim_bridge import scaling
from sim_bridge.lake import ISOLATED_REGION, Lake, in_isolated_region, isolated_region

__all__ = ["ISOLATED_REGION", "Floor", "Lake", "ReachableMap", "TeachingSet", "data_dir",
           "in_isolated_region", "isolated_region",
           "load_benchmark_goals", "load_floor", "load_reachable_casts", "load_reachable_map",
           "load_teaching_set", "teaching_set_problem"]

REACHABLE_MAP = "reachable_map.npz"
BENCHMARK_GOALS = "benchmark_goals.npz"
TEACHING_SET = "teaching_set.npz"
BENCHMARK_FLOOR = "benchmark_floor.npz"
# The map stores actions as int16 = round(action * ACTION_SCALE) (half the size of float32).
ACTION_SCALE = 32767


def data_dir() -> Path:
    """The first existing data directory among the known layouts."""
    here = Path(__file__).resolve().parent
    candidates = []
    if os.environ.get("SIM_BRIDGE_DATA_DIR"):
        candidates.append(Path(os.environ["SIM_BRIDGE_DATA_DIR"]))
    candidates += [
        here / "data",  # package_data layout
        here.parent / "data",  # source tree: sim_bridge/data
        *(p / "share" / "sim_bridge" / "data" for p in here.parents),  # colcon install
    ]
    for c in candidates:
        if (c / BENCHMARK_GOALS).is_file() or (c / REACHABLE_MAP).is_file():
            return c
    raise FileNotFoundError(f"no sim_bridge data directory among {[str(c) for c in candidates]}")


def _path(name: str, path: str | os.PathLike[str] | None) -> Path:
    return Path(path) if path is not None else data_dir() / name


@dataclass(frozen=True)
class TeachingSet:
    """Demonstrations: the most repeatable recorded action of each coarse cell."""

    actions: np.ndarray  # (M, 24)
    outcomes: np.ndarray  # (M, 2) mean outcome over the repeats
    spread: np.ndarray  # (M,) mean distance of the repeats to their mean


@dataclass(frozen=True)
class ReachableMap:
    """Every landed cast of the mapping run."""

    actions: np.ndarray  # (N, 24) float32 (stored as int16, see ACTION_SCALE)
    outcomes: np.ndarray  # (N, 2) float32, normalised


def load_reachable_map(path: str | os.PathLike[str] | None = None,
                       lake: Lake | None = None) -> np.ndarray:
    """Reached outcomes (N, 2) of the mapping run (with ``lake``: on its water only)."""
    return load_reachable_casts(path, lake).outcomes


def load_reachable_casts(path: str | os.PathLike[str] | None = None,
                         lake: Lake | None = None) -> ReachableMap:
    """Actions and outcomes of the mapping run; with ``lake``, only its water landings.

    The map was recorded in the default world; the physics does not depend on the lake, so in a
    world whose water is a subset of the default's (a smaller pond) a mapped cast is a landing
    there exactly when its outcome lies on that world's water.
    """
    with np.load(_path(REACHABLE_MAP, path)) as f:
        actions = f["actions"]
        if actions.dtype == np.int16:
            actions = (actions / np.float32(f["action_scale"])).astype(np.float32)
        m = ReachableMap(actions=actions, outcomes=f["outcomes"])
    if lake is None:
        return m
    keep = lake.is_water(scaling.outcome_to_world(m.outcomes.astype(np.float64)))
    return ReachableMap(actions=m.actions[keep], outcomes=m.outcomes[keep])


def load_benchmark_goals(path: str | os.PathLike[str] | None = None) -> np.ndarray:
    """Benchmark goals (N, 2): one per 26 x 16 cell holding reached points."""
    with np.load(_path(BENCHMARK_GOALS, path)) as f:
        return f["goals"]


def load_teaching_set(path: str | os.PathLike[str] | None = None) -> TeachingSet:
    """The teacher's demonstrations."""
    with np.load(_path(TEACHING_SET, path)) as f:
        return TeachingSet(actions=f["actions"], outcomes=f["outcomes"], spread=f["spread"])


TEACHING_SET_FORMAT = (f"a teaching set (.npz: actions (M, {scaling.ACTION_DIM}) and outcomes "
                       f"(M, {scaling.OUTCOME_DIM}) in [-1, 1], spread (M,))")


def teaching_set_problem(path: str | os.PathLike[str],
                         action_size: int = scaling.ACTION_DIM,
                         outcome_size: int = scaling.OUTCOME_DIM) -> str | None:
    """Why a file the user names is not a teaching set of this world, or None.

    The nodes' `teaching_set` parameter is checked with it before any node starts
    (sgim_ros.params.DataFile): any other file (a text file, another world's set, a set
    with NaN) would otherwise stop the teacher, or the run, at its first movement.
    """
    try:
        with open(path, "rb") as head:
            if head.read(4) != b"PK\x03\x04":
                return "not an .npz archive (a zip of .npy arrays, as numpy.savez writes)"
        with np.load(path, allow_pickle=False) as f:
            missing = [k for k in ("actions", "outcomes", "spread") if k not in f.files]
            if missing:
                return f"it has no {', '.join(missing)} array (it holds {', '.join(f.files)})"
            actions, outcomes, spread = f["actions"], f["outcomes"], f["spread"]
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as error:
        return f"not an .npz archive numpy reads ({str(error).splitlines()[0][:120]})"
    arrays = {"actions": actions, "outcomes": outcomes, "spread": spread}
    for name, array in arrays.items():
        if not np.issubdtype(array.dtype, np.number) or np.issubdtype(array.dtype,
                                                                       np.complexfloating):
            return f"{name} holds {array.dtype}, not real numbers"
    m = len(actions) if actions.ndim else 0
    if m < 1 or actions.shape != (m, action_size):
        return f"actions has shape {actions.shape}, expected (M >= 1, {action_size})"
    if outcomes.shape != (m, outcome_size):
        return f"outcomes has shape {outcomes.shape}, expected ({m}, {outcome_size})"
    if spread.shape != (m,):
        return f"spread has shape {spread.shape}, expected ({m},)"
    for name, array in arrays.items():
        if not np.all(np.isfinite(array)):
            return f"{name} holds NaN or infinite numbers"
    for name in ("actions", "outcomes"):
        if np.any(np.abs(arrays[name]) > 1.0):
            return f"{name} has numbers outside [-1, 1]"
    return None


@dataclass(frozen=True)
class Floor:
    """What a nearest-action lookup on the reachable map achieves on each benchmark goal.

    ``per_goal`` is the floor: of the ``k`` mapped landings nearest the goal, the action with
    the least error over ``choose_casts`` noisy casts, scored on ``score_casts`` others.
    ``nearest``: the single nearest landing's action, scored the same way (the simplest lookup).
    Same goals, same order as ``load_benchmark_goals()`` (``goals`` is kept to check it).
    Made by ``python -m sim_bridge.tools.make_floor``.
    """

    goals: np.ndarray  # (N, 2)
    per_goal: np.ndarray  # (N,)
    nearest: np.ndarray  # (N,)
    k: int
    choose_casts: int
    score_casts: int

    @property
    def mean(self) -> float:
        """The floor of the benchmark: the mean over goals, as a learner's error is."""
        return float(self.per_goal.mean())

    @property
    def nearest_mean(self) -> float:
        return float(self.nearest.mean())


def load_floor(path: str | os.PathLike[str] | None = None) -> Floor:
    """The benchmark's floor (``benchmark_floor.npz``, beside the benchmark goals)."""
    with np.load(_path(BENCHMARK_FLOOR, path)) as f:
        return Floor(goals=f["goals"], per_goal=f["per_goal"], nearest=f["nearest"],
                     k=int(f["k"]), choose_casts=int(f["choose_casts"]),
                     score_casts=int(f["score_casts"]))
