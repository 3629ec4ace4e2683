"""Build the teaching set: on a coarse grid over the reached area's bounding box, in each cell
holding reached points, the recorded action whose outcome varies least over repeated casts.

Why the most repeatable action: a demonstration is only useful to the learner if imitating it
lands where it says; an action in a chaotic part of the action space would teach noise. An action
is never chosen unless every repeat lands on water and the mean of its repeats (the demonstrated
outcome) lies on reached water (``make_benchmark_set.on_reached_water``): on a lake's thin arm
the mean of water landings could lie on the bank. Saved per entry: the action, the mean outcome
of its repeats, their spread (mean distance to the mean) and its group.

Why the isolated region is one group of its own: a coarse cell can hold both main-lake and
isolated landings, and the few isolated candidates would lose the draw; a teacher can only show
the isolated region if the teaching set holds it, so its landings (``lake.in_isolated_region``)
form one extra group, whatever coarse cells it straddles (one entry, not one per cell). Near the
shore many candidates fail, so each group tries up to ``--max-candidates`` recorded actions (in
a random order) until ``--candidates`` of them passed.

Why one random stream per group (seeds ``[seed, group]``): any entry can be rebuilt alone from
the map (a test rebuilds some), and a change in one group leaves the others as they were.

    python -m sim_bridge.tools.make_teaching_set --seed 0

``--pond-radius R`` (metres) builds the set for a world whose pond is smaller (``lake.Lake``):
the stored map's casts are kept only where they land on that world's water, the pond group is
that pond's landings, and the repeats are cast in that world. ``--pond-min-landed K``: for the
pond group only, the repeats that must land on water (default: all).
"""

from __future__ import annotations

import argparse

import numpy as np
from tqdm import tqdm

from sgim_ros.command_line import BriefParser
from sim_bridge.data_files import load_reachable_casts
from sim_bridge.fishing_world import FishingWorld, Status
from sim_bridge.lake import DEFAULT_LAKE, Lake, lake_with_pond_radius
from sim_bridge.tools.make_benchmark_set import grid_cells, on_reached_water

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
    own) for the isolated region's landings, whatever cells it straddles."""
    _, _, idx = grid_cells(outcomes, grid)
    cell = idx[:, 0] * grid[1] + idx[:, 1]
    return np.where(lake.in_isolated_region(outcomes), grid[0] * grid[1], cell)


def group_seed(seed: int, group: int) -> int:
    return int(np.random.SeedSequence([seed, group]).generate_state(1)[0])


def teaching_entry(world: FishingWorld, actions: np.ndarray, outcomes: np.ndarray,
                   members: np.ndarray, group: int, candidates: int, repeats: int, seed: int,
                   max_candidates: int, min_landed: int | None = None
                   ) -> tuple[np.ndarray, np.ndarray, float] | None:
    """(action, mean outcome, spread) of one group's most repeatable passing candidate, or None.

    ``members``: indices of the group's mapped landings; ``outcomes``: every mapped landing (the
    reached area that a demonstrated outcome must lie in)."""
    rng = np.random.default_rng(group_seed(seed, group))
    world.reseed(group_seed(seed, group))
    best: tuple[float, np.ndarray | None, np.ndarray | None] = (float("inf"), None, None)
    passed = 0
    for p in rng.permutation(members)[:max_candidates]:
        a = actions[p].astype(np.float64)
        mean, spread = repeat_spread(world, a, repeats, min_landed)
        if np.isfinite(spread) and not on_reached_water(mean, outcomes, world.lake)[0]:
            spread = float("inf")
        passed += bool(np.isfinite(spread))
        if spread < best[0]:
            best = (spread, a, mean)
        if passed >= candidates:
            break
    return None if best[1] is None else (best[1], best[2], best[0])


def teaching_set(actions: np.ndarray, outcomes: np.ndarray, grid: tuple[int, int],
                 candidates: int, repeats: int, seed: int, max_candidates: int = 30,
                 progress: bool = True, lake: Lake = DEFAULT_LAKE,
                 pond_min_landed: int | None = None, groups: list[int] | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Actions (M, 24), mean outcomes (M, 2), spreads (M,) and groups (M,) of the chosen
    demonstrations, in group order; ``groups``: build only these groups' entries."""
    outcomes = np.asarray(outcomes, dtype=np.float64)
    pond_group = grid[0] * grid[1]
    group = teaching_groups(outcomes, grid, lake)
    todo = np.unique(group) if groups is None else np.array(sorted(groups))
    chosen: list[tuple[np.ndarray, np.ndarray, float, int]] = []
    with FishingWorld(seed=seed, lake=lake) as world:
        for g in tqdm(todo, desc="groups", disable=not progress):
            entry = teaching_entry(world, actions, outcomes, np.flatnonzero(group == g), int(g),
                                   candidates, repeats, seed, max_candidates,
                                   pond_min_landed if g == pond_group else None)
            if entry is not None:
                chosen.append((*entry, int(g)))
    return (np.array([c[0] for c in chosen]), np.array([c[1] for c in chosen]),
            np.array([c[2] for c in chosen]), np.array([c[3] for c in chosen], dtype=int))


def main(argv: list[str] | None = None) -> None:
    parser = BriefParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reachable", default=None, help="map .npz (default: the stored one)")
    parser.add_argument("--grid", type=int, nargs=2, default=GRID, help="cells in x and y")
    parser.add_argument("--candidates", type=int, default=6,
                        help="recorded actions per group that must pass before choosing")
    parser.add_argument("--max-candidates", type=int, default=30,
                        help="recorded actions tried at most per group")
    parser.add_argument("--repeats", type=int, default=10, help="noisy casts per candidate (>=10)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--pond-radius", type=float, default=None,
                        help="radius (m) of the isolated pond of the world (default: the "
                             "default world's)")
    parser.add_argument("--pond-min-landed", type=int, default=None,
                        help="pond group only: repeats that must land on water (default: all)")
    parser.add_argument("--output", default="sim_bridge/data/teaching_set.npz")
    args = parser.parse_args(argv)
    lake = lake_with_pond_radius(args.pond_radius)
    casts = load_reachable_casts(args.reachable, lake=None if lake.is_default else lake)
    a, o, s, g = teaching_set(casts.actions, casts.outcomes, tuple(args.grid), args.candidates,
                              args.repeats, args.seed, args.max_candidates, lake=lake,
                              pond_min_landed=args.pond_min_landed)
    extra = {} if lake.is_default else {"pond_radius": lake.pond[2]}
    if args.pond_min_landed is not None:
        extra["pond_min_landed"] = args.pond_min_landed
    np.savez_compressed(args.output, actions=a, outcomes=o, spread=s, group=g, seed=args.seed,
                        grid=np.array(args.grid), repeats=args.repeats,
                        candidates=args.candidates, max_candidates=args.max_candidates, **extra)
    pond = np.flatnonzero(lake.in_isolated_region(o))
    n_groups = len(np.unique(teaching_groups(casts.outcomes.astype(np.float64),
                                             tuple(args.grid), lake)))
    print(f"{len(a)} demonstrations ({n_groups} groups) -> {args.output}; spread median "
          f"{np.median(s):.4f}; in the isolated region: entries {pond.tolist()} at "
          f"{np.round(o[pond], 3).tolist()}")


if __name__ == "__main__":
    main()
