"""Measure how hard and how learnable the fishing world is (figures quoted in README_world.md).

Why: the world must pose the paper's problem (redundant, noisy, with a natural landing zone and
an isolated region that random actions rarely reach) yet stay learnable (small action changes
move the landing point a little, and the time step does not decide where it lands). Every figure
is in normalised outcome units.

    PYTHONPATH=sim_bridge .venv/bin/python benchmarks/measure_world.py --casts 5000

``--solver gauss-seidel`` measures the same figures with the world's previous constraint solver
(MLCP with 50 projected Gauss-Seidel sweeps; the world's own is Dantzig's pivoting since issue
32), so that the two worlds can still be compared (bench_sim_speed.py, ``set_solver``).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from bench_sim_speed import SOLVERS, set_solver

from sim_bridge.data_files import (
    ISOLATED_REGION,
    in_isolated_region,
    load_benchmark_goals,
    load_reachable_map,
    load_teaching_set,
)
from sim_bridge.fishing_world import FishingWorld, Status
from sim_bridge.lake import draw_shoreline
from sim_bridge.scaling import world_to_outcome

SOLVER = "shipped"
"""The constraint solver of every world built here (--solver)."""


def build(**kwargs) -> FishingWorld:
    """A FishingWorld with the solver --solver names."""
    world = FishingWorld(**kwargs)
    if SOLVER != "shipped":
        set_solver(world, SOLVER)
    return world


def ok_outcomes(world: FishingWorld, actions: np.ndarray) -> np.ndarray:
    """Outcomes (n, 2), NaN rows where the cast did not land."""
    out = np.full((len(actions), 2), np.nan)
    for i, a in enumerate(actions):
        r = world.execute(a)
        if r.status == Status.OK:
            out[i] = r.outcome
    return out


def touch_downs(world: FishingWorld, actions: np.ndarray) -> np.ndarray:
    """Normalised touch-down points (n, 2), on water or on land; NaN rows if never down.

    The learnability figures (sensitivity, dt halving) measure the physics, which does not care
    whether the hook comes down on water or on the shore, so they use every touch-down.
    """
    out = np.full((len(actions), 2), np.nan)
    for i, a in enumerate(actions):
        r = world.execute(a)
        if r.world_point is not None:
            out[i] = world_to_outcome(r.world_point)
    return out


def sensitivity(n_actions: int, delta: float, seed: int) -> np.ndarray:
    """Landing shift when one action number changes by ``delta`` (noise-free), all 24 numbers."""
    rng = np.random.default_rng(seed)
    world = build(seed=seed, noise=0.0)
    shifts = []
    for a in rng.uniform(-1, 1, (n_actions, world.action_dim)):
        base = touch_downs(world, a[None])[0]
        moved = []
        for d in range(world.action_dim):
            b = a.copy()
            b[d] += delta if b[d] + delta <= 1.0 else -delta
            moved.append(b)
        out = touch_downs(world, np.array(moved))
        shifts.extend(np.linalg.norm(out - base, axis=1))
    s = np.array(shifts)
    return s[np.isfinite(s)]


def dt_halving(n_actions: int, seed: int, dt: float = 1 / 240) -> np.ndarray:
    """Landing shift between time step ``dt`` and ``dt / 2`` (noise-free)."""
    acts = np.random.default_rng(seed).uniform(-1, 1, (n_actions, 24))
    a = touch_downs(build(seed=seed, noise=0.0, time_step=dt), acts)
    b = touch_downs(build(seed=seed, noise=0.0, time_step=dt / 2), acts)
    s = np.linalg.norm(a - b, axis=1)
    return s[np.isfinite(s)]


def paper_noise(n_actions: int = 20, repeats: int = 10, seed: int = 0,
                noise: float | None = None) -> float:
    """The paper's protocol: mean over actions of the mean distance of attempts to their mean.

    The paper's hook always landed on water; ours may touch down on the shore. The noise is that
    of the rig (motor commands -> touch-down point), so every touch-down counts, on water or on
    land (``world_point`` in normalised units); casts that never come down are skipped.
    """
    rng = np.random.default_rng(seed + 1)
    world = build(seed=seed) if noise is None else build(seed=seed, noise=noise)
    spreads = []
    for a in rng.uniform(-1, 1, (n_actions, world.action_dim)):
        pts = [world_to_outcome(r.world_point) for r in (world.execute(a) for _ in range(repeats))
               if r.world_point is not None]
        if len(pts) >= 2:
            out = np.array(pts)
            spreads.append(np.mean(np.linalg.norm(out - out.mean(axis=0), axis=1)))
    return float(np.mean(spreads))


def pile_up(points: np.ndarray, radius: float = 0.2) -> tuple[np.ndarray, float]:
    """Densest point (the most crowded radius-ball among the casts) and its share of casts."""
    sub = points[:: max(1, len(points) // 2000)]
    d = np.linalg.norm(sub[:, None, :] - points[None, :, :], axis=2)
    counts = (d < radius).sum(axis=1)
    best = int(np.argmax(counts))
    return sub[best], counts[best] / len(points)


def rare_cells(points: np.ndarray, reachable: np.ndarray, nx: int = 26, ny: int = 16,
               share: float = 0.1) -> tuple[float, int]:
    """Share of casts landing in the rarest ``share`` of the grid cells that hold reached points."""
    def cells(p: np.ndarray) -> np.ndarray:
        ix = np.clip(((p[:, 0] + 1) / 2 * nx).astype(int), 0, nx - 1)
        iy = np.clip(((p[:, 1] + 1) / 2 * ny).astype(int), 0, ny - 1)
        return ix * ny + iy
    reach = np.unique(cells(reachable))
    counts = np.bincount(cells(points), minlength=nx * ny)[reach]
    k = max(1, round(share * len(reach)))
    rarest = np.argsort(counts, kind="stable")[:k]
    return counts[rarest].sum() / len(points), k


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--casts", type=int, default=5000, help="random casts for the histogram")
    parser.add_argument("--sens-actions", type=int, default=20, help="actions x 24 perturbations")
    parser.add_argument("--dt-actions", type=int, default=100, help="actions for dt halving")
    parser.add_argument("--noise-seeds", type=int, default=12,
                        help="seeds of the noise protocol (it varies a lot with the 20 actions)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--reachable", default=None,
                        help="reachable map .npz (default: sim_bridge/data/reachable_map.npz)")
    parser.add_argument("--png", default="docs/figures/sim_random_casts.png")
    parser.add_argument("--solver", choices=SOLVERS, default="shipped",
                        help="constraint solver of the worlds measured: the world's own "
                        "(Dantzig's pivoting), 'dantzig' or 'gauss-seidel' (the previous one; "
                        "bench_sim_speed.py)")
    args = parser.parse_args(argv)
    global SOLVER
    SOLVER = args.solver
    t0 = time.perf_counter()
    s = sensitivity(args.sens_actions, 1e-3, args.seed)
    print(f"sensitivity (1e-3 on one action number, {len(s)} pairs): median {np.median(s):.4f}, "
          f"p90 {np.percentile(s, 90):.4f}, max {s.max():.3f}")
    h = dt_halving(args.dt_actions, args.seed)
    print(f"dt 1/240 -> 1/480 ({len(h)} actions): median {np.median(h):.4f}, "
          f"p90 {np.percentile(h, 90):.4f}, max {h.max():.3f}")
    noises = [paper_noise(seed=args.seed + k) for k in range(args.noise_seeds)]
    print(f"noise, paper protocol (20 actions x 10 attempts, touch-downs on water or land), "
          f"seeds {args.seed}..{args.seed + args.noise_seeds - 1}: "
          f"{[round(v, 4) for v in noises]}, mean {np.mean(noises):.4f}")
    world = build(seed=args.seed)
    acts = np.random.default_rng(args.seed + 7).uniform(-1, 1, (args.casts, 24))
    out = np.full((args.casts, 2), np.nan)
    status, on_land = np.zeros(args.casts, int), np.zeros(args.casts, bool)
    for i, a in enumerate(acts):
        r = world.execute(a)
        status[i] = r.status
        on_land[i] = r.status == Status.NO_CONTACT and r.world_point is not None
        if r.status == Status.OK:
            out[i] = r.outcome
    landed = status == Status.OK
    pts = out[landed]
    never_down = (status == Status.NO_CONTACT).mean() - on_land.mean()
    print(f"random casts: {args.casts}; on water {landed.mean():.3f}, on land "
          f"{on_land.mean():.3f}, never down {never_down:.3f}, physics failures "
          f"{(status == Status.PHYSICS_FAILURE).mean():.3f}")
    centre, share = pile_up(pts)
    print(f"densest point {np.round(centre, 3).tolist()}: share within 0.2 = {share:.3f} of the "
          f"water landings, {share * landed.mean():.3f} of all random casts")
    reach = pts
    if args.reachable != "none":
        try:
            reach = load_reachable_map(args.reachable)
        except FileNotFoundError:
            print("(no reachable map: using these casts as the reachable set)")
    rare, k = rare_cells(pts, reach)
    print(f"share of random casts in the {k} rarest reachable 26x16 cells: "
          f"{rare * landed.mean():.4f} of all ({rare:.4f} of the water landings)")
    pond = in_isolated_region(pts)
    print(f"isolated region {ISOLATED_REGION}: {int(pond.sum())} casts, share "
          f"{pond.sum() / args.casts:.4f} of all random casts")
    try:
        goals, teach = load_benchmark_goals(), load_teaching_set()
        in_pond = np.flatnonzero(in_isolated_region(teach.outcomes))
        print(f"data files: {len(reach)} mapped water landings, {len(goals)} benchmark goals "
              f"({int(in_isolated_region(goals).sum())} in the isolated region), "
              f"{len(teach.actions)} teaching entries; in the isolated region: entries "
              f"{in_pond.tolist()} at {np.round(teach.outcomes[in_pond], 3).tolist()}")
    except FileNotFoundError:
        print("(no data files)")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 5.4))
    hist = ax.hist2d(pts[:, 0], pts[:, 1], bins=[52, 52], range=[[-1, 1], [-1, 1]],
                     cmap="viridis", cmin=1)
    fig.colorbar(hist[3], ax=ax, label="casts per bin")
    draw_shoreline(ax)
    circle = plt.Circle(ISOLATED_REGION["centre"], ISOLATED_REGION["radius"], fill=False,
                        ls="--", lw=1.6, color="tab:orange", zorder=3)
    ax.add_patch(circle)
    ax.set(xlim=(-1, 1), ylim=(-1, 1), aspect="equal", xlabel="outcome x (normalised)",
           ylabel="outcome y (normalised)",
           title=f"{len(pts)} of {args.casts} random casts on water (seed {args.seed});\n"
                 f"red: shoreline, dashed: isolated pond")
    fig.tight_layout()
    fig.savefig(args.png, dpi=80)
    print(f"histogram -> {args.png}; {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
