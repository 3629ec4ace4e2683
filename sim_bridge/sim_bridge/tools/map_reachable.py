"""Map the reachable water densely: random casts, casts spread from the sparsest cells, and a
targeted search around the casts that reached the isolated region.

Why three phases: random actions pile up in the natural landing zone, so uniform sampling alone
leaves the arms of the lake and the isolated pond with a handful of points. The spread phase
re-casts small perturbations (std ``--sigma``) of actions that landed in the least visited cells
of a 26 x 16 grid (a landing is drawn as parent with weight 1 / landings in its cell), which
fills the arms to their tips. The pond is ringed by land, so perturbing main-lake casts never
reaches it; the isolated phase re-casts small perturbations (std ``--pond-sigma``) of the casts
that did land in it (parents: every pond landing so far, the new ones included), so that the
benchmark, the teaching set and the floor find landings there. Only water landings are outcomes:
casts that land on land or never come down are counted, not saved.

Everything follows from ``--seed`` (actions, parents, perturbations and the world's noise): the
same command writes the same file, byte for byte. Actions are stored as int16 (action x 32767:
at most 1.5e-5 from the cast action, a landing shift of about 1e-5 by the measured sensitivity)
so that about 12,000 landings fit in well under 1 MB; ``data_files`` returns them as floats.

    python -m sim_bridge.tools.map_reachable --random 10000 --spread 6000 --pond 1500 --seed 0

``--pond-radius R`` (metres) maps a world whose isolated pond is smaller (``lake.Lake``); its
random phase may then find no pond landing (the pond phase then stops with an error).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from tqdm import tqdm

from sgim_ros.command_line import BriefParser
from sim_bridge.data_files import ACTION_SCALE
from sim_bridge.fishing_world import FishingWorld, Status
from sim_bridge.lake import DEFAULT_LAKE, Lake, lake_with_pond_radius

GRID = (26, 16)


def cell_index(outcomes: np.ndarray, grid: tuple[int, int] = GRID) -> np.ndarray:
    """Cell number of each normalised outcome on a grid over [-1, 1]^2."""
    nx, ny = grid
    ix = np.clip(((outcomes[:, 0] + 1) / 2 * nx).astype(int), 0, nx - 1)
    iy = np.clip(((outcomes[:, 1] + 1) / 2 * ny).astype(int), 0, ny - 1)
    return ix * ny + iy


class _Mapper:
    """Casts actions, keeps the water landings, counts the rest."""

    def __init__(self, world: FishingWorld, bar: tqdm) -> None:
        self.world, self.bar = world, bar
        self.actions: list[np.ndarray] = []
        self.outcomes: list[np.ndarray] = []
        self.land = self.no_water = self.failed = 0

    def cast(self, a: np.ndarray) -> bool:
        r = self.world.execute(a)
        self.bar.update()
        if r.status == Status.OK:
            self.actions.append(a)
            self.outcomes.append(r.outcome)
            return True
        if r.status == Status.NO_CONTACT and r.world_point is not None:
            self.land += 1
        elif r.status == Status.NO_CONTACT:
            self.no_water += 1
        else:
            self.failed += 1
        return False


def run_mapping(n_random: int, n_spread: int, seed: int, sigma: float = 0.05,
                n_pond: int = 0, pond_sigma: float = 0.01, progress: bool = True,
                lake: Lake = DEFAULT_LAKE) -> tuple[np.ndarray, np.ndarray, dict[str, int]]:
    """Actions (N, 24), outcomes (N, 2) of every water landing, and counts of each phase."""
    rng = np.random.default_rng(seed)
    world = FishingWorld(seed=seed, lake=lake)
    in_isolated_region = lake.in_isolated_region
    bar = tqdm(total=n_random + n_spread + n_pond, desc="casts", disable=not progress)
    m = _Mapper(world, bar)
    for a in rng.uniform(-1, 1, (n_random, world.action_dim)):
        m.cast(a)
    stats = {"random_water": len(m.outcomes), "random_land": m.land,
             "random_pond": int(in_isolated_region(np.array(m.outcomes).reshape(-1, 2)).sum())}
    done = 0
    while done < n_spread:
        batch = min(500, n_spread - done)
        cells = cell_index(np.array(m.outcomes))
        counts = np.bincount(cells, minlength=GRID[0] * GRID[1])
        weight = 1.0 / counts[cells]  # favour casts whose cell is sparsely visited
        parents = rng.choice(len(cells), size=batch, p=weight / weight.sum())
        for p in parents:
            m.cast(np.clip(m.actions[p] + sigma * rng.standard_normal(world.action_dim), -1, 1))
        done += batch
    n_before = len(m.outcomes)
    done = 0
    while done < n_pond:  # parents: every pond landing so far, the new ones included
        batch = min(100, n_pond - done)
        pond = np.flatnonzero(in_isolated_region(np.array(m.outcomes)))
        if len(pond) == 0:
            raise RuntimeError("no cast reached the isolated pond: raise --random or --spread")
        for p in rng.choice(pond, size=batch):
            a = m.actions[p] + pond_sigma * rng.standard_normal(world.action_dim)
            m.cast(np.clip(a, -1, 1))
        done += batch
    bar.close()
    world.close()
    outcomes = np.array(m.outcomes, dtype=np.float32)
    stats |= {"pond_phase_water": len(outcomes) - n_before,
              "pond_phase_pond": int(in_isolated_region(outcomes[n_before:]).sum()),
              "water": len(outcomes), "land": m.land, "no_water": m.no_water,
              "failed": m.failed, "pond": int(in_isolated_region(outcomes).sum())}
    return np.array(m.actions), outcomes, stats


def save_png(outcomes: np.ndarray, path: Path, title: str, lake: Lake = DEFAULT_LAKE) -> None:
    """Scatter of the reached outcomes, the isolated pond's in orange, and the shoreline."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sim_bridge.lake import draw_shoreline
    fig, ax = plt.subplots(figsize=(6, 5.6))
    pond = lake.in_isolated_region(outcomes)
    ax.scatter(outcomes[~pond, 0], outcomes[~pond, 1], s=1, alpha=0.3, label="main lake")
    ax.scatter(outcomes[pond, 0], outcomes[pond, 1], s=2, alpha=0.7, color="tab:orange",
               label="isolated pond")
    draw_shoreline(ax, lake=lake)
    ax.set(xlim=(-1, 1), ylim=(-1, 1), aspect="equal", xlabel="outcome x (normalised)",
           ylabel="outcome y (normalised)", title=title)
    ax.legend(loc="upper right", fontsize=7, markerscale=6)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    parser = BriefParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--random", type=int, default=10000, help="uniform random casts")
    parser.add_argument("--spread", type=int, default=6000, help="casts spread from sparse cells")
    parser.add_argument("--sigma", type=float, default=0.05, help="perturbation std (action units)")
    parser.add_argument("--pond", type=int, default=1500,
                        help="casts perturbing the actions that reached the isolated pond")
    parser.add_argument("--pond-sigma", type=float, default=0.01,
                        help="perturbation std of the pond search (action units)")
    parser.add_argument("--seed", type=int, default=0, help="seed of actions and world noise")
    parser.add_argument("--pond-radius", type=float, default=None,
                        help="radius (m) of the isolated pond of the world (default: the "
                             "default world's)")
    parser.add_argument("--output", default="sim_bridge/data/reachable_map.npz")
    parser.add_argument("--png", default="docs/figures/sim_reachable_map.png")
    args = parser.parse_args(argv)
    if min(args.random, args.spread, args.pond) < 0 or args.random < 1:
        parser.error("--random must be >= 1, --spread and --pond >= 0")
    lake = lake_with_pond_radius(args.pond_radius)
    actions, outcomes, stats = run_mapping(args.random, args.spread, args.seed, args.sigma,
                                           args.pond, args.pond_sigma, lake=lake)
    extra = {} if lake.is_default else {"pond_radius": lake.pond[2]}
    np.savez_compressed(args.output, actions=np.round(actions * ACTION_SCALE).astype(np.int16),
                        action_scale=ACTION_SCALE, outcomes=outcomes, seed=args.seed,
                        n_random=args.random, n_spread=args.spread, n_pond=args.pond,
                        sigma=args.sigma, pond_sigma=args.pond_sigma, **extra)
    save_png(outcomes, Path(args.png), f"{len(outcomes)} water landings (seed {args.seed})",
             lake)
    size = Path(args.output).stat().st_size
    print(f"{len(outcomes)} water landings -> {args.output} ({size / 1e6:.2f} MB), {args.png}; "
          f"{stats}")


if __name__ == "__main__":
    main()
