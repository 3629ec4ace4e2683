"""How hard and how learnable the fishing world is: random casts and probes of its physics
(experiments/world_jobs.py, world_probes.py), for sim_bridge/README_world.md.

Blocks: `random-casts` (where uniformly random actions come down: the natural landing zone,
the rarely reached cells) with the histogram `sim_random_casts.png`; `learnability` (a nudged
action number, a halved time step); `noise` (the paper's protocol, seed by seed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sgim_nodes.experiments import world_jobs
from sgim_nodes.experiments.pinned import Experiment
from sgim_nodes.experiments.reports import Report

FIGURE = "sim_random_casts.png"
PAPER_NOISE = 0.073  # Nguyen et al. 2011, their rig's noise with this protocol
CROWD_RADIUS = 0.2  # normalised units: the natural landing zone's ball
GRID = (26, 16)  # the reachable map's cells (sim_bridge/data_files.py)
RARE_SHARE = 0.1


def make(experiment: Experiment, runs_dir: Path, figures_dir: Path) -> Report:
    made: dict[str, list] = {}
    for job in experiment.world_jobs:
        found = world_jobs.read_result(world_jobs.result_path(runs_dir, job))
        if found is None:
            raise FileNotFoundError(f"{job.name} is not made yet: run the experiment first")
        kind = job.kind if isinstance(job, world_jobs.Probe) else "casts"
        made.setdefault(kind, []).append((job, found))
    report = Report()
    page = experiment.pages[0]
    if "casts" in made:
        points = np.concatenate([found["points"] for _, found in made["casts"]])
        report.add(page, "random-casts", random_casts(points))
        report.figures.append(histogram(points, figures_dir / FIGURE))
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


def _outcomes(points: np.ndarray) -> np.ndarray:
    from sim_bridge.scaling import world_to_outcome

    return np.asarray([world_to_outcome(p) for p in points], float).reshape(-1, 2)


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
    """The share of `points` in the rarest RARE_SHARE of the GRID cells that reachable
    outcomes fill, and how many cells that is."""
    nx, ny = GRID

    def cell(p: np.ndarray) -> np.ndarray:
        ix = np.clip(((p[:, 0] + 1) / 2 * nx).astype(int), 0, nx - 1)
        iy = np.clip(((p[:, 1] + 1) / 2 * ny).astype(int), 0, ny - 1)
        return ix * ny + iy

    filled = np.unique(cell(reachable))
    counts = np.bincount(cell(points), minlength=nx * ny)[filled]
    k = max(1, round(RARE_SHARE * len(filled)))
    return float(np.sort(counts, kind="stable")[:k].sum() / len(points)), k


def random_casts(points: np.ndarray) -> str:
    from sim_bridge.data_files import load_reachable_map

    n = len(points)
    down = np.isfinite(points[:, 0])
    water = _water(points)
    landed = _outcomes(points[water])
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


def histogram(points: np.ndarray, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sim_bridge.data_files import ISOLATED_REGION
    from sim_bridge.lake import draw_shoreline

    landed = _outcomes(points[_water(points)])
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
    shifts = np.concatenate([found["values"] for _, found in made])
    jobs = [job for job, _ in made]
    actions = sum(job.actions for job in jobs)
    what = (f"one action number moved by 0.001, noise off ({actions} actions x 24 numbers)"
            if kind == "sensitivity" else
            f"the time step halved, 1/240 -> 1/480 s, noise off ({actions} actions)")
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
