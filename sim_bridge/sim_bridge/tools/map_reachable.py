"""Map the reachable outcomes: random casts, then casts spread from the sparsest cells.

Why two phases: random actions pile up in the natural landing zone, so uniform sampling alone
leaves the rare regions with a handful of points. The second phase re-casts small perturbations
of actions that landed in the least visited cells of a 26 x 16 grid, which fills those regions.
Saves the landed casts (actions and normalised outcomes, float32) as a compressed .npz and a PNG.

    python -m sim_bridge.tools.map_reachable --random 8000 --spread 4000 --seed 0
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from tqdm import tqdm

from sim_bridge.fishing_world import FishingWorld, Status

GRID = (26, 16)


def cell_index(outcomes: np.ndarray, grid: tuple[int, int] = GRID) -> np.ndarray:
    """Cell number of each normalised outcome on a grid over [-1, 1]^2."""
    nx, ny = grid
    ix = np.clip(((outcomes[:, 0] + 1) / 2 * nx).astype(int), 0, nx - 1)
    iy = np.clip(((outcomes[:, 1] + 1) / 2 * ny).astype(int), 0, ny - 1)
    return ix * ny + iy


def run_mapping(n_random: int, n_spread: int, seed: int, sigma: float = 0.05,
                progress: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Actions (N, 24) and outcomes (N, 2) of every landed cast."""
    rng = np.random.default_rng(seed)
    world = FishingWorld(seed=seed)
    actions, outcomes = [], []
    bar = tqdm(total=n_random + n_spread, desc="casts", disable=not progress)
    for a in rng.uniform(-1, 1, (n_random, world.action_dim)):
        r = world.execute(a)
        if r.status == Status.OK:
            actions.append(a)
            outcomes.append(r.outcome)
        bar.update()
    done = 0
    while done < n_spread:
        batch = min(500, n_spread - done)
        cells = cell_index(np.array(outcomes))
        counts = np.bincount(cells, minlength=GRID[0] * GRID[1])
        weight = 1.0 / counts[cells]  # favour casts whose cell is sparsely visited
        parents = rng.choice(len(cells), size=batch, p=weight / weight.sum())
        for p in parents:
            a = np.clip(actions[p] + sigma * rng.standard_normal(world.action_dim), -1, 1)
            r = world.execute(a)
            if r.status == Status.OK:
                actions.append(a)
                outcomes.append(r.outcome)
            bar.update()
        done += batch
    bar.close()
    world.close()
    return np.array(actions, dtype=np.float32), np.array(outcomes, dtype=np.float32)


def save_png(outcomes: np.ndarray, path: Path, title: str) -> None:
    """Scatter of the reached outcomes."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 5))
    ax.scatter(outcomes[:, 0], outcomes[:, 1], s=1, alpha=0.3)
    ax.set(xlim=(-1, 1), ylim=(-1, 1), xlabel="outcome x (normalised)",
           ylabel="outcome y (normalised)", title=title)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--random", type=int, default=8000, help="uniform random casts")
    parser.add_argument("--spread", type=int, default=4000, help="casts spread from sparse cells")
    parser.add_argument("--sigma", type=float, default=0.05, help="perturbation std (action units)")
    parser.add_argument("--seed", type=int, default=0, help="seed of actions and world noise")
    parser.add_argument("--output", default="sim_bridge/data/reachable_map.npz")
    parser.add_argument("--png", default="docs/figures/sim_reachable_map.png")
    args = parser.parse_args(argv)
    actions, outcomes = run_mapping(args.random, args.spread, args.seed, args.sigma)
    np.savez_compressed(args.output, actions=actions, outcomes=outcomes,
                        seed=args.seed, n_random=args.random, n_spread=args.spread)
    save_png(outcomes, Path(args.png), f"{len(outcomes)} reached points (seed {args.seed})")
    print(f"{len(outcomes)} landed casts -> {args.output}, {args.png}")


if __name__ == "__main__":
    main()
