"""Build the benchmark goals the paper's way: a 26 x 16 grid over the bounding box of the reached
area, and in every cell that movements reach, one goal drawn uniformly in the cell's reached water.

Why "reached water": the paper drew its 129 goals in the reachable part of the outcome space. A
point drawn anywhere in a cell that holds reached points may lie on land (38 of the 129 goals of
the first benchmark did) or on water no cast reaches. Here the reached area is the water within
``REACH_RADIUS`` of a mapped landing (``reachable_map.npz``): a goal is drawn uniformly in its
cell until it falls there (rejection sampling; after ``MAX_TRIES`` misses, a mapped landing of
the cell, drawn uniformly, is the goal).

Why from the saved map: the set is a pure function of the map's outcomes and the seed, so anyone
can regenerate the stored file exactly (a test does).

    python -m sim_bridge.tools.make_benchmark_set --seed 0

``--pond-radius R`` (metres): the goals of a world whose pond is smaller (``lake.Lake``), from
the stored map's landings on that world's water.
"""

from __future__ import annotations

import argparse

import numpy as np

from sgim_ros.command_line import BriefParser
from sim_bridge import scaling
from sim_bridge.data_files import load_reachable_map
from sim_bridge.lake import DEFAULT_LAKE, Lake, lake_with_pond_radius

GRID = (26, 16)
# Normalised units (0.26 m): well under the world's noise (about 0.07 by the paper's protocol),
# and the typical gap between neighbouring mapped landings in the sparsest reached cells.
REACH_RADIUS = 0.03
MAX_TRIES = 10_000
VALIDATION_SEED = 7
"""Seed of the validation goals: other points of the same cells, on which a choice is judged
so that it is never made on the benchmark's own goals (the arms use seed 7 likewise)."""


def grid_cells(points: np.ndarray, grid: tuple[int, int] = GRID
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(low corner, cell size, (N, 2) cell of every point) of a grid over the points' box."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    size = (hi - lo) / np.array(grid)
    idx = np.minimum(((points - lo) / size).astype(int), np.array(grid) - 1)
    return lo, size, idx


def on_reached_water(points: np.ndarray, reached: np.ndarray, lake: Lake = DEFAULT_LAKE,
                     radius: float = REACH_RADIUS) -> np.ndarray:
    """True for normalised points (N, 2) on the lake's water within ``radius`` of a landing."""
    points = np.atleast_2d(np.asarray(points, dtype=np.float64))
    near = np.array([np.min(np.linalg.norm(reached - p, axis=1)) <= radius for p in points])
    return near & lake.is_water(scaling.outcome_to_world(points))


def benchmark_goals(reached: np.ndarray, seed: int, grid: tuple[int, int] = GRID,
                    lake: Lake = DEFAULT_LAKE) -> np.ndarray:
    """One goal in the reached water of every grid cell holding reached points (cell order:
    x-major, as sorted); the same map and seed always give the same goals."""
    reached = np.asarray(reached, dtype=np.float64)
    lo, size, idx = grid_cells(reached, grid)
    rng = np.random.default_rng(seed)
    goals = []
    for cell in sorted({(int(i), int(j)) for i, j in idx}):
        members = reached[(idx[:, 0] == cell[0]) & (idx[:, 1] == cell[1])]
        # landings within reach of this cell (a goal near its edge may be reached from next door)
        box_lo, box_hi = lo + np.array(cell) * size, lo + (np.array(cell) + 1) * size
        near = reached[np.all((reached > box_lo - REACH_RADIUS)
                              & (reached < box_hi + REACH_RADIUS), axis=1)]
        for _ in range(MAX_TRIES):
            g = box_lo + rng.uniform(0.0, 1.0, 2) * size
            if on_reached_water(g, near, lake)[0]:
                break
        else:
            g = members[rng.integers(len(members))]
        goals.append(g)
    return np.array(goals)


def validation_goals(reached: np.ndarray, lake: Lake = DEFAULT_LAKE) -> np.ndarray:
    """The benchmark's cells, other points in them (``VALIDATION_SEED``); not stored: a pure
    function of the map, like the benchmark itself."""
    return benchmark_goals(reached, VALIDATION_SEED, lake=lake)


def main(argv: list[str] | None = None) -> None:
    parser = BriefParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reachable", default=None, help="map .npz (default: the stored one)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the goal draws")
    parser.add_argument("--pond-radius", type=float, default=None,
                        help="radius (m) of the isolated pond of the world (default: the "
                             "default world's)")
    parser.add_argument("--output", default="sim_bridge/data/benchmark_goals.npz")
    args = parser.parse_args(argv)
    lake = lake_with_pond_radius(args.pond_radius)
    reached = load_reachable_map(args.reachable, lake=None if lake.is_default else lake)
    goals = benchmark_goals(reached, args.seed, lake=lake)
    extra = {} if lake.is_default else {"pond_radius": lake.pond[2]}
    np.savez_compressed(args.output, goals=goals, seed=args.seed, grid=np.array(GRID),
                        reach_radius=REACH_RADIUS, **extra)
    pond = lake.in_isolated_region(goals)
    print(f"{len(goals)} benchmark goals -> {args.output}; {int(pond.sum())} in the isolated "
          f"region; all on reached water: {bool(on_reached_water(goals, reached, lake).all())}")


if __name__ == "__main__":
    main()
