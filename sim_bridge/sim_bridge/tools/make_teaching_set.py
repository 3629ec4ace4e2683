"""Build the teaching set: on a coarse grid over the reachable area's bounding box, in each cell
holding reached points, the recorded action whose outcome varies least over repeated casts.

Why the most repeatable action: a demonstration is only useful to the learner if imitating it
lands where it says; an action in a chaotic part of the action space would teach noise. Saved per
cell: the action, the mean outcome of its repeats and their spread (mean distance to the mean).

    python -m sim_bridge.tools.make_teaching_set --grid 7 5 --candidates 6 --repeats 10 --seed 0
"""

from __future__ import annotations

import argparse

import numpy as np
from tqdm import tqdm

from sim_bridge.data_files import load_reachable_casts
from sim_bridge.fishing_world import FishingWorld, Status


def repeat_spread(world: FishingWorld, action: np.ndarray,
                  repeats: int) -> tuple[np.ndarray, float]:
    """Mean outcome and spread of ``repeats`` noisy casts (inf spread if any fails to land)."""
    out = []
    for _ in range(repeats):
        r = world.execute(action)
        if r.status != Status.OK:
            return np.full(2, np.nan), float("inf")
        out.append(r.outcome)
    o = np.array(out)
    mean = o.mean(axis=0)
    return mean, float(np.mean(np.linalg.norm(o - mean, axis=1)))


def teaching_set(actions: np.ndarray, outcomes: np.ndarray, grid: tuple[int, int],
                 candidates: int, repeats: int, seed: int, progress: bool = True
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Actions (M, 24), mean outcomes (M, 2), spreads (M,) of the chosen demonstrations."""
    lo, hi = outcomes.min(axis=0), outcomes.max(axis=0)
    size = (hi - lo) / np.array(grid)
    idx = np.minimum(((outcomes - lo) / size).astype(int), np.array(grid) - 1)
    cell = idx[:, 0] * grid[1] + idx[:, 1]
    rng = np.random.default_rng(seed)
    world = FishingWorld(seed=seed)
    chosen_a, chosen_o, chosen_s = [], [], []
    for c in tqdm(np.unique(cell), desc="cells", disable=not progress):
        members = np.flatnonzero(cell == c)
        picks = rng.choice(members, size=min(candidates, len(members)), replace=False)
        best = (float("inf"), None, None)
        for p in picks:
            a = actions[p].astype(np.float64)
            mean, spread = repeat_spread(world, a, repeats)
            if spread < best[0]:
                best = (spread, a, mean)
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
    parser.add_argument("--grid", type=int, nargs=2, default=(7, 5), help="cells in x and y")
    parser.add_argument("--candidates", type=int, default=6, help="recorded actions tried per cell")
    parser.add_argument("--repeats", type=int, default=10, help="noisy casts per candidate (>=10)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--output", default="sim_bridge/data/teaching_set.npz")
    args = parser.parse_args(argv)
    casts = load_reachable_casts(args.reachable)
    a, o, s = teaching_set(casts.actions, casts.outcomes, tuple(args.grid), args.candidates,
                           args.repeats, args.seed)
    np.savez_compressed(args.output, actions=a, outcomes=o, spread=s, seed=args.seed,
                        grid=np.array(args.grid), repeats=args.repeats)
    print(f"{len(a)} demonstrations -> {args.output}; spread median {np.median(s):.4f}")


if __name__ == "__main__":
    main()
