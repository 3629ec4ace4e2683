"""Build the benchmark goals as in the paper: a 26 x 16 grid over the reachable area's bounding
box, one uniformly drawn goal in each cell that holds reached points (the paper got 129).

Why from the saved map: the set is a pure function of the reachable map and the seed, so anyone
can regenerate the stored file exactly (a test does).

    python -m sim_bridge.tools.make_benchmark_set --seed 0

``--pond-radius R`` (metres): the goals of a world whose pond is smaller (``lake.Lake``), from
the stored map's casts that land on that world's water.
"""

from __future__ import annotations

import argparse

import numpy as np
from tqdm import tqdm

from sim_bridge.data_files import load_reachable_map
from sim_bridge.lake import lake_with_pond_radius

GRID = (26, 16)


def benchmark_goals(reached: np.ndarray, seed: int, grid: tuple[int, int] = GRID,
                    progress: bool = False) -> np.ndarray:
    """One random goal in every grid cell (over the points' bounding box) holding a point."""
    reached = np.asarray(reached, dtype=np.float64)
    lo, hi = reached.min(axis=0), reached.max(axis=0)
    size = (hi - lo) / np.array(grid)
    idx = np.minimum(((reached - lo) / size).astype(int), np.array(grid) - 1)
    occupied = sorted({(int(i), int(j)) for i, j in idx})
    rng = np.random.default_rng(seed)
    goals = [lo + (np.array(c) + rng.uniform(0, 1, 2)) * size
             for c in tqdm(occupied, desc="cells", disable=not progress)]
    return np.array(goals)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reachable", default=None, help="map .npz (default: the stored one)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the goal draws")
    parser.add_argument("--pond-radius", type=float, default=None,
                        help="radius (m) of the isolated pond of the world (default: 0.95)")
    parser.add_argument("--output", default="sim_bridge/data/benchmark_goals.npz")
    args = parser.parse_args(argv)
    lake = lake_with_pond_radius(args.pond_radius)
    reached = load_reachable_map(args.reachable, lake=None if lake.is_default else lake)
    goals = benchmark_goals(reached, args.seed, progress=True)
    extra = {} if lake.is_default else {"pond_radius": lake.pond[2]}
    np.savez_compressed(args.output, goals=goals, seed=args.seed, grid=np.array(GRID), **extra)
    print(f"{len(goals)} benchmark goals -> {args.output}")


if __name__ == "__main__":
    main()
