"""Build the floor of the benchmark: per goal, the error that looking up the reachable map's
nearest landings achieves when their actions are cast again with the world's noise.

Why: a learner's error on the benchmark means little without the error that is possible at all.
The world is noisy (the paper's protocol measures about 0.07), so even an action that once landed
exactly on a goal lands a noise's width away when cast again. The floor is a simple lookup on a
dense map of the world (``reachable_map.npz``, about 10,000 water landings): no learner that
only knows fewer casts should be expected below it (measuring-the-learner.md).

Per goal ``i`` (its own noise stream, seed ``[seed, i]``, so any goal can be recomputed alone):
- the ``k`` mapped landings nearest the goal give ``k`` candidate actions;
- ``nearest``: the nearest landing's action, cast ``--score-casts`` times: the mean error;
- ``best of k``: each candidate cast ``--choose-casts`` times, the one of least mean error kept,
  then scored on ``--score-casts`` further casts (held back from the choice, so the choice's luck
  does not flatter it). This is the floor (``data_files.load_floor().per_goal``).
An error is the distance from the goal to where the hook came down, on water or on land (the
evaluator's rule); a cast that never comes down counts as the diagonal of [-1, 1]^2.

    python -m sim_bridge.tools.make_floor --seed 0

``--png-only`` redraws the figure (goals coloured by their floor, the teaching set, the shore)
and prints the summary from the stored files, without casting.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from tqdm import tqdm

from sgim_ros.command_line import BriefParser
from sim_bridge.data_files import (
    load_benchmark_goals,
    load_floor,
    load_reachable_casts,
    load_teaching_set,
)
from sim_bridge.fishing_world import FishingWorld
from sim_bridge.scaling import world_to_outcome

FAILURE_DISTANCE = 2.0 * math.sqrt(2.0)  # the evaluator's: a cast that never came down


def cast_errors(world: FishingWorld, action: np.ndarray, goal: np.ndarray, casts: int
                ) -> np.ndarray:
    """Distances from ``goal`` to ``casts`` noisy touch-downs of ``action``."""
    out = np.empty(casts)
    for j in range(casts):
        r = world.execute(action)
        out[j] = (FAILURE_DISTANCE if r.world_point is None
                  else float(np.linalg.norm(world_to_outcome(r.world_point) - goal)))
    return out


def nearest_landings(outcomes: np.ndarray, goals: np.ndarray, k: int) -> np.ndarray:
    """Indices (len(goals), k) of the ``k`` mapped outcomes nearest each goal, nearest first
    (ties by index: a stable sort)."""
    d = np.linalg.norm(goals[:, None, :] - outcomes[None, :, :], axis=2)
    return np.argsort(d, axis=1, kind="stable")[:, :k]


def goal_seed(seed: int, index: int) -> int:
    """The noise seed of goal ``index``: independent streams, each reproducible alone."""
    return int(np.random.SeedSequence([seed, index]).generate_state(1)[0])


def floor_of_goal(world: FishingWorld, goal: np.ndarray, candidates: np.ndarray,
                  choose_casts: int, score_casts: int, seed: int, index: int
                  ) -> tuple[float, float, int]:
    """(nearest error, best-of-k error on held-back casts, chosen candidate) for one goal."""
    world.reseed(goal_seed(seed, index))
    nearest = float(cast_errors(world, candidates[0], goal, score_casts).mean())
    chosen = int(np.argmin([cast_errors(world, a, goal, choose_casts).mean()
                            for a in candidates]))
    best = float(cast_errors(world, candidates[chosen], goal, score_casts).mean())
    return nearest, best, chosen


def floor(goals: np.ndarray, actions: np.ndarray, outcomes: np.ndarray, k: int,
          choose_casts: int, score_casts: int, seed: int, indices: list[int] | None = None,
          progress: bool = True) -> dict[str, np.ndarray]:
    """The floor of every goal (or of ``indices`` only): arrays keyed as in the saved file."""
    goals = np.asarray(goals, dtype=np.float64)
    near = nearest_landings(np.asarray(outcomes, dtype=np.float64), goals, k)
    rows = list(range(len(goals))) if indices is None else list(indices)
    res = np.empty((len(rows), 3))
    with FishingWorld(seed=seed) as world:
        for n, i in enumerate(tqdm(rows, desc="goals", disable=not progress)):
            res[n] = floor_of_goal(world, goals[i], actions[near[i]].astype(np.float64),
                                   choose_casts, score_casts, seed, i)
    return {"nearest": res[:, 0], "best": res[:, 1], "chosen": res[:, 2].astype(int),
            "neighbours": near[rows],
            "neighbour_distance": np.linalg.norm(outcomes[near[rows, 0]] - goals[rows], axis=1)}


def summary(path: str | None = None) -> str:
    """The stored floor's figures: overall, main lake and isolated region."""
    from sim_bridge.lake import in_isolated_region
    f = load_floor(path)
    iso = in_isolated_region(f.goals)
    rows = [f"floor of {len(f.goals)} goals: best of {f.k} nearest (chosen on {f.choose_casts} "
            f"casts, scored on {f.score_casts} others) mean {f.mean:.4f} (median "
            f"{np.median(f.per_goal):.4f}); nearest landing's action mean {f.nearest_mean:.4f} "
            f"(median {np.median(f.nearest):.4f})"]
    for name, sel in (("main lake", ~iso), ("isolated region", iso)):
        rows.append(f"  {name}: {int(sel.sum())} goals, floor mean {f.per_goal[sel].mean():.4f},"
                    f" nearest mean {f.nearest[sel].mean():.4f}")
    return "\n".join(rows)


def save_png(path: str, floor_path: str | None = None, goals_path: str | None = None) -> None:
    """Benchmark goals coloured by their floor, the teaching set's outcomes, the shoreline."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sim_bridge.lake import ISOLATED_REGION, draw_shoreline
    floor, goals, teach = load_floor(floor_path), load_benchmark_goals(goals_path), \
        load_teaching_set()
    fig, ax = plt.subplots(figsize=(6.4, 5.6))
    draw_shoreline(ax)
    sc = ax.scatter(goals[:, 0], goals[:, 1], c=floor.per_goal, s=22, cmap="viridis",
                    vmin=0.0, vmax=float(np.percentile(floor.per_goal, 95)), zorder=3,
                    label=f"{len(goals)} benchmark goals")
    fig.colorbar(sc, ax=ax, label="floor: error of the best mapped action, cast with noise")
    ax.scatter(teach.outcomes[:, 0], teach.outcomes[:, 1], marker="*", s=90, color="tab:red",
               edgecolor="black", linewidth=0.5, zorder=4,
               label=f"{len(teach.outcomes)} demonstrations")
    ax.add_patch(plt.Circle(ISOLATED_REGION["centre"], ISOLATED_REGION["radius"], fill=False,
                            ls="--", color="tab:orange", lw=1.4, zorder=2))
    ax.set(xlim=(-1, 1), ylim=(-1, 1), aspect="equal", xlabel="outcome x (normalised)",
           ylabel="outcome y (normalised)",
           title=f"Benchmark floor: mean {floor.mean:.3f} (nearest landing alone "
                 f"{floor.nearest_mean:.3f});\ndashed: the isolated region")
    ax.legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    parser = BriefParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reachable", default=None, help="map .npz (default: the stored one)")
    parser.add_argument("--goals", default=None, help="benchmark .npz (default: the stored one)")
    parser.add_argument("--k", type=int, default=3, help="nearest mapped landings per goal")
    parser.add_argument("--choose-casts", type=int, default=10,
                        help="noisy casts per candidate to choose the best of k")
    parser.add_argument("--score-casts", type=int, default=20,
                        help="noisy casts that score the nearest and the chosen action")
    parser.add_argument("--seed", type=int, default=0, help="seed of the casts' noise")
    parser.add_argument("--output", default="sim_bridge/data/benchmark_floor.npz")
    parser.add_argument("--png", default="docs/figures/sim_benchmark_floor.png")
    parser.add_argument("--png-only", action="store_true",
                        help="only redraw --png from the stored files (no casting)")
    args = parser.parse_args(argv)
    if min(args.k, args.choose_casts, args.score_casts) < 1:
        parser.error("--k, --choose-casts and --score-casts must be >= 1")
    if args.png_only:
        save_png(args.png, args.output, args.goals)
        print(f"{summary(args.output)}\nfigure -> {args.png}")
        return
    goals = load_benchmark_goals(args.goals)
    casts = load_reachable_casts(args.reachable)
    f = floor(goals, casts.actions, casts.outcomes, args.k, args.choose_casts,
              args.score_casts, args.seed)
    np.savez_compressed(args.output, goals=goals, per_goal=f["best"], nearest=f["nearest"],
                        chosen=f["chosen"], neighbours=f["neighbours"],
                        neighbour_distance=f["neighbour_distance"], k=args.k,
                        choose_casts=args.choose_casts, score_casts=args.score_casts,
                        seed=args.seed, map_size=len(casts.outcomes))
    save_png(args.png, args.output, args.goals)
    print(f"{summary(args.output)}\n  nearest mapped landing "
          f"{f['neighbour_distance'].mean():.4f} from a goal on average\n-> {args.output}, "
          f"{args.png}")


if __name__ == "__main__":
    main()
