"""How hard and how learnable the fishing world is: random casts and probes of its physics
(experiments/world_jobs.py, world_probes.py), for sim_bridge/README_world.md.

Blocks: `random-casts` (where uniformly random actions come down: the natural landing zone,
the rarely reached cells) with the histogram `sim_random_casts.png`; `learnability` (a nudged
action number, a halved time step); `noise` (the paper's protocol, seed by seed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sgim_nodes.experiments import shipped, world_jobs
from sgim_nodes.experiments.pinned import Experiment
from sgim_nodes.experiments.reports import Report

FIGURE = "sim_random_casts.png"
PAPER_NOISE = 0.073  # Nguyen et al. 2011, their rig's noise with this protocol
CROWD_RADIUS = 0.2  # normalised units: the natural landing zone's ball
RARE_SHARE = 0.1  # of the reachable map's cells (sim_bridge/tools/map_reachable.py's GRID)


def make(experiment: Experiment, runs_dir: Path, figures_dir: Path) -> Report:
    made: dict[str, list] = {}
    for job in experiment.world_jobs:
        found = shipped.read_result(experiment, runs_dir, job)
        if found is None:
            raise FileNotFoundError(f"{job.name} is not made yet: run the experiment first")
        kind = job.kind if isinstance(job, world_jobs.Probe) else "casts"
        made.setdefault(kind, []).append((job, found))
    report = Report()
    page = experiment.pages[0]
    if "casts" in made:
        points = np.concatenate([found["points"] for _, found in made["casts"]])
        water = _water(points)
        report.add(page, "random-casts", random_casts(points, water))
        report.figures.append(histogram(points, water, figures_dir / FIGURE))
    probes = [learnability_row(kind, made[kind]) for kind in ("sensitivity", "time_step")
              if kind in made]
    if probes:
        report.add(page, "learnability", "\n".join(
            ["| probe | touch-down shifts | median | p90 | max |", "|---|---|---|---|---|",
             *probes]))
    if "noise" in made:
        report.add(page, "noise", noise_rows(made["noise"]))
    return report


def _water(points: np.ndarray) -> np.ndarray:
    """Which touch-downs (world metres) are on water; NaN rows (never down) are not."""
    from sim_bridge.lake import DEFAULT_LAKE

    down = np.isfinite(points[:, 0])
    water = np.zeros(len(points), bool)
    water[down] = DEFAULT_LAKE.water_body(points[down]) > 0
    return water


def densest(points: np.ndarray, radius: float = CROWD_RADIUS) -> tuple[np.ndarray, float]:
    """The most crowded `radius` ball centred on one of the points (at most 2000 centres
    tried, evenly spread), and the share of the points in it."""
    centres = points[:: max(1, len(points) // 2000)]
    inside = np.zeros(len(centres), int)
    for start in range(0, len(points), 5000):  # bounded memory for large samples
        chunk = points[start:start + 5000]
        inside += (np.linalg.norm(centres[:, None] - chunk[None], axis=2) < radius).sum(axis=1)
    best = int(np.argmax(inside))
    return centres[best], inside[best] / len(points)


def rarest_cells(points: np.ndarray, reachable: np.ndarray) -> tuple[float, int]:
    """The share of `points` in the rarest RARE_SHARE of the reachable map's grid cells that
    reachable outcomes fill, and how many cells that is."""
    from sim_bridge.tools.map_reachable import GRID, cell_index

    filled = np.unique(cell_index(reachable))
    counts = np.bincount(cell_index(points), minlength=GRID[0] * GRID[1])[filled]
    k = max(1, round(RARE_SHARE * len(filled)))
    return float(np.sort(counts, kind="stable")[:k].sum() / len(points)), k


def random_casts(points: np.ndarray, water: np.ndarray) -> str:
    """The shares of `points` (world metres) on water (`water`), on land and never down; the
    natural landing zone; the rarely reached cells."""
    from sim_bridge.data_files import load_reachable_map
    from sim_bridge.scaling import world_to_outcome
    from sim_bridge.tools.map_reachable import GRID

    n = len(points)
    down = np.isfinite(points[:, 0])
    landed = world_to_outcome(points[water])
    centre, share = densest(landed)
    rare, cells = rarest_cells(landed, np.asarray(load_reachable_map(), float))
    rows = ["| what | figure |", "|---|---|",
            f"| random casts | {n:,}: **{100 * water.mean():.1f} %** on water, "
            f"{100 * (down & ~water).mean():.1f} % on land, "
            f"{100 * (~down).mean():.2f} % never came down |",
            f"| the natural landing zone | within {CROWD_RADIUS} of ({centre[0]:.3f}, "
            f"{centre[1]:.3f}): **{share:.3f}** of the water landings, "
            f"{share * water.mean():.3f} of all casts |",
            f"| the rarest {cells} of the {GRID[0]} x {GRID[1]} cells reachable outcomes "
            f"fill | **{rare * water.mean():.4f}** of all casts |"]
    return "\n".join(rows)


def histogram(points: np.ndarray, water: np.ndarray, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sim_bridge.data_files import ISOLATED_REGION
    from sim_bridge.lake import draw_shoreline
    from sim_bridge.scaling import world_to_outcome

    landed = world_to_outcome(points[water])
    fig, ax = plt.subplots(figsize=(6.4, 5.4))
    hist = ax.hist2d(landed[:, 0], landed[:, 1], bins=[52, 52], range=[[-1, 1], [-1, 1]],
                     cmap="viridis", cmin=1)
    fig.colorbar(hist[3], ax=ax, label="casts per bin")
    draw_shoreline(ax)
    ax.add_patch(plt.Circle(ISOLATED_REGION["centre"], ISOLATED_REGION["radius"], fill=False,
                            ls="--", lw=1.6, color="tab:orange", zorder=3))
    ax.set(xlim=(-1, 1), ylim=(-1, 1), aspect="equal", xlabel="outcome x (normalised)",
           ylabel="outcome y (normalised)",
           title=f"{len(landed):,} of {len(points):,} random casts on water;\n"
                 "red: shoreline, dashed: isolated pond")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def learnability_row(kind: str, made: list) -> str:
    from sgim_nodes.experiments.world_probes import DELTA
    from sim_bridge.fishing_world import DEFAULT_TIME_STEP
    from sim_bridge.scaling import ACTION_DIM

    shifts = np.concatenate([found["values"] for _, found in made])
    actions = sum(job.actions for job, _ in made)
    step = round(1 / DEFAULT_TIME_STEP)
    what = (f"one action number moved by {DELTA:g}, noise off ({actions} actions x "
            f"{ACTION_DIM} numbers)" if kind == "sensitivity" else
            f"the time step halved, 1/{step} -> 1/{2 * step} s, noise off ({actions} actions)")
    return (f"| {what} | {len(shifts)} | **{np.median(shifts):.4f}** | "
            f"**{np.percentile(shifts, 90):.4f}** | {shifts.max():.3f} |")


def noise_rows(made: list) -> str:
    from scipy import stats

    made = sorted(made, key=lambda pair: pair[0].seed)
    per_seed = np.array([found["values"].mean() for _, found in made])
    job = made[0][0]
    half = (stats.t.ppf(0.975, len(per_seed) - 1) * per_seed.std(ddof=1)
            / np.sqrt(len(per_seed))) if len(per_seed) > 1 else float("nan")
    rows = ["| what | figure |", "|---|---|",
            f"| protocol | {job.actions} random actions x {job.attempts} casts each, the mean "
            "distance of the touch-downs to their mean, averaged over the actions |",
            "| seed by seed | " + ", ".join(f"{v:.4f}" for v in per_seed) + " |",
            f"| mean of {len(per_seed)} seeds | **{per_seed.mean():.4f}** +- {half:.4f} "
            f"(95 %; the paper's rig: {PAPER_NOISE}) |"]
    return "\n".join(rows)
