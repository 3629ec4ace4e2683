"""Build the teaching set: on a coarse grid over the reachable area's bounding box, in each cell
holding reached points, the recorded action whose outcome varies least over repeated casts.

Why the most repeatable action: a demonstration is only useful to the learner if imitating it
lands where it says; an action in a chaotic part of the action space would teach noise. An action
whose repeats do not all land on water (some land on the shore) is never chosen. Saved per entry:
the action, the mean outcome of its repeats and their spread (mean distance to the mean).

Why the isolated pond is one group of its own: a coarse cell can hold both main-lake and pond
landings, and the few pond candidates would lose the draw; a teacher can only show the pond if the
teaching set holds it, so the pond's landings (``lake.in_isolated_region``) form one extra group,
whatever coarse cells the pond straddles (one entry, not one per straddled cell). Near the shore
many candidates fail, so each group tries up to ``--max-candidates`` recorded actions until
``--candidates`` of them landed every repeat on water.

    python -m sim_bridge.tools.make_teaching_set --grid 10 7 --candidates 6 --repeats 10 --seed 0

``--pond-radius R`` (metres) builds the set for a world whose pond is smaller (``lake.Lake``):
the stored map's casts are kept only where they land on that world's water, the pond group is
that pond's landings, and the repeats are cast in that world (so a pond entry must land all its
repeats in the small pond). Without it, the default world, as before.
"""

from __future__ import annotations

import argparse

import numpy as np
from tqdm import tqdm

from sim_bridge.data_files import load_reachable_casts
from sim_bridge.fishing_world import FishingWorld, Status
from sim_bridge.lake import DEFAULT_LAKE, Lake, lake_with_pond_radius

GRID = (10, 7)


def repeat_spread(world: FishingWorld, action: np.ndarray, repeats: int,
                  min_landed: int | None = None) -> tuple[np.ndarray, float]:
    """Mean outcome and spread of ``repeats`` noisy casts; inf spread if fewer than
    ``min_landed`` (default: all) land on water. Mean and spread are over the landed casts."""
    need = repeats if min_landed is None else min_landed
    out = []
    for i in range(repeats):
        r = world.execute(action)
        if r.status == Status.OK:
            out.append(r.outcome)
        elif len(out) + repeats - i - 1 < need:  # can no longer reach ``need``
            return np.full(2, np.nan), float("inf")
    o = np.array(out)
    mean = o.mean(axis=0)
    return mean, float(np.mean(np.linalg.norm(o - mean, axis=1)))


def teaching_groups(outcomes: np.ndarray, grid: tuple[int, int],
                    lake: Lake = DEFAULT_LAKE) -> np.ndarray:
    """Group number of every outcome: its coarse cell, or ``grid[0] * grid[1]`` (one group of its
    own) for the isolated pond's landings, whatever cells the pond straddles."""
    lo, hi = outcomes.min(axis=0), outcomes.max(axis=0)
    size = (hi - lo) / np.array(grid)
    idx = np.minimum(((outcomes - lo) / size).astype(int), np.array(grid) - 1)
    cell = idx[:, 0] * grid[1] + idx[:, 1]
    return np.where(lake.in_isolated_region(outcomes), grid[0] * grid[1], cell)


def teaching_set(actions: np.ndarray, outcomes: np.ndarray, grid: tuple[int, int],
                 candidates: int, repeats: int, seed: int, max_candidates: int = 30,
                 progress: bool = True, lake: Lake = DEFAULT_LAKE,
                 pond_min_landed: int | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Actions (M, 24), mean outcomes (M, 2), spreads (M,) of the chosen demonstrations.

    ``pond_min_landed``: for the pond's group only, the repeats that must land on water (default
    all); a pond smaller than the noise's spread has no action that lands there every time."""
    pond_group = grid[0] * grid[1]
    group = teaching_groups(np.asarray(outcomes, dtype=np.float64), grid, lake)
    rng = np.random.default_rng(seed)
    world = FishingWorld(seed=seed, lake=lake)
    chosen_a, chosen_o, chosen_s = [], [], []
    for g in tqdm(np.unique(group), desc="cells", disable=not progress):
        members = rng.permutation(np.flatnonzero(group == g))[:max_candidates]
        best, landed = (float("inf"), None, None), 0
        for p in members:
            a = actions[p].astype(np.float64)
            mean, spread = repeat_spread(world, a, repeats,
                                         pond_min_landed if g == pond_group else None)
            landed += bool(np.isfinite(spread))
            if spread < best[0]:
                best = (spread, a, mean)
            if landed >= candidates:
                break
        if best[1] is not None:
            chosen_s.append(best[0])
            chosen_a.append(best[1])
            chosen_o.append(best[2])
    world.close()
    return np.array(chosen_a), np.array(chosen_o), np.array(chosen_s)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reachable", default=None, help="map .npz (default: the stored one)")
    parser.add_argument("--grid", type=int, nargs=2, default=GRID, help="cells in x and y")
    parser.add_argument("--candidates", type=int, default=6,
                        help="recorded actions per group whose repeats all landed on water")
    parser.add_argument("--max-candidates", type=int, default=30,
                        help="recorded actions tried at most per group")
    parser.add_argument("--repeats", type=int, default=10, help="noisy casts per candidate (>=10)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--pond-radius", type=float, default=None,
                        help="radius (m) of the isolated pond of the world (default: the "
                             "default world's, 0.95)")
    parser.add_argument("--pond-min-landed", type=int, default=None,
                        help="pond group only: repeats that must land on water (default: all)")
    parser.add_argument("--output", default="sim_bridge/data/teaching_set.npz")
    args = parser.parse_args(argv)
    lake = lake_with_pond_radius(args.pond_radius)
    casts = load_reachable_casts(args.reachable, lake=None if lake.is_default else lake)
    a, o, s = teaching_set(casts.actions, casts.outcomes, tuple(args.grid), args.candidates,
                           args.repeats, args.seed, args.max_candidates, lake=lake,
                           pond_min_landed=args.pond_min_landed)
    extra = {} if lake.is_default else {"pond_radius": lake.pond[2]}
    if args.pond_min_landed is not None:
        extra["pond_min_landed"] = args.pond_min_landed
    np.savez_compressed(args.output, actions=a, outcomes=o, spread=s, seed=args.seed,
                        grid=np.array(args.grid), repeats=args.repeats, **extra)
    pond = np.flatnonzero(lake.in_isolated_region(o))
    print(f"{len(a)} demonstrations -> {args.output}; spread median {np.median(s):.4f}; "
          f"in the isolated pond: entries {pond.tolist()} at {np.round(o[pond], 3).tolist()}")


if __name__ == "__main__":
    main()
