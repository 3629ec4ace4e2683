"""The learners' benchmark (experiments/learners.yaml) as docs/learners.md's blocks."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sgim_nodes.core.learner_registry import RANDOM, RANDOM_GOALS, SAGGRIAC, SGIM_D
from sgim_nodes.core.learner_registry import colour as learner_colour
from sgim_nodes.experiments import runner_jobs, shipped
from sgim_nodes.experiments.pinned import Experiment
from sgim_nodes.experiments.reports import Report
from sgim_nodes.provenance.record import made_on

COMPARISONS = ((RANDOM_GOALS, RANDOM), (SAGGRIAC, RANDOM), (SAGGRIAC, RANDOM_GOALS),
               (SGIM_D, SAGGRIAC))
"""The tests issue 10 asked for: goal babbling against motor babbling, the interest against
uniform goals, the teacher against none."""
FIGURE = "learners_error_curves.png"


def frame_means(shares: np.ndarray) -> np.ndarray | None:
    """Mean over runs of each frame's share, NaN where no run drew a mode-1 goal in that
    frame; None when no run drew one at all (a learner without mode 1)."""
    seen = ~np.isnan(shares)
    if not seen.any():
        return None
    counts = seen.sum(0)
    sums = np.where(seen, shares, 0.0).sum(0)
    return np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)


def figure(results: list[dict], floors: dict[str, float], eval_every: int, path: Path) -> Path:
    """Mean error curve per learner with its 95 % band, one panel per world, floor dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from scipy import stats

    names = list(dict.fromkeys(r["world"] for r in results))
    fig, axes = plt.subplots(1, len(names), figsize=(5.5 * len(names), 4), squeeze=False)
    for ax, name in zip(axes[0], names, strict=True):
        rows = [r for r in results if r["world"] == name]
        for lr in dict.fromkeys(r["learner"] for r in rows):
            curves = np.array([r["curve"] for r in rows if r["learner"] == lr])
            x = np.arange(curves.shape[1]) * eval_every
            m = curves.mean(0)
            h = (stats.t.ppf(0.975, len(curves) - 1) * curves.std(0, ddof=1)
                 / np.sqrt(len(curves))) if len(curves) > 1 else 0 * m
            colour = learner_colour(lr) or "tab:gray"  # as in every figure of the learner
            ax.plot(x, m, label=lr, color=colour)
            ax.fill_between(x, m - h, m + h, alpha=0.2, color=colour)
        if np.isfinite(floors.get(name, np.nan)):
            ax.axhline(floors[name], color="k", ls="--", lw=1, label="floor")
        seeds = len(rows) // max(1, len({r["learner"] for r in rows}))
        ax.set(title=f"{name} ({seeds} seeds)", xlabel="movements",
               ylabel="mean distance to test goals", yscale="log")
        ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def load_results(experiment: Experiment, runs_dir: Path) -> list[dict]:
    out = []
    for job in experiment.runner_jobs:
        found = shipped.read_result(experiment, runs_dir, job)
        if found is None:
            raise FileNotFoundError(f"{job.name} is not made yet: run the experiment first")
        out.append(found | {"world": job.world, "learner": job.learner, "seed": job.seed})
    return out


def _by(results: list[dict], world: str) -> dict[str, list[dict]]:
    rows: dict[str, list[dict]] = {}
    for r in results:
        if r["world"] == world:
            rows.setdefault(r["learner"], []).append(r)
    return rows


def _interval(values: list[float]) -> str:
    from sgim_nodes.analysis.statistics import mean_ci

    ci = mean_ci(values)
    return f"{ci.mean:.4f} [{ci.low:.4f}, {ci.high:.4f}]"


def final_errors(results: list[dict], floors: dict[str, float]) -> str:
    lines = ["| world | learner | n | final error [95 % interval] | ratio to the floor | "
             "demonstrations per run |", "|---|---|---|---|---|---|"]
    for world in dict.fromkeys(r["world"] for r in results):
        for learner, rows in _by(results, world).items():
            finals = [r["final"] for r in rows]
            floor = floors[world]
            ratio = f"{np.mean(finals) / floor:.2f}" if np.isfinite(floor) else "n/a"
            demos = sorted({r["n_demonstrations"] for r in rows})
            shown = (f"{demos[0]}" if len(demos) == 1 else f"{demos[0]}-{demos[-1]}")
            lines.append(f"| {world} | {learner} | {len(rows)} | {_interval(finals)} | {ratio} "
                         f"| {shown} |")
    floors_line = ", ".join(f"{w} {f:.4f}" for w, f in floors.items())
    return "\n".join(lines) + f"\n\nThe floor (the best a perfect learner does): {floors_line}."


def same_memory(results: list[dict]) -> str:
    lines = ["| world | learner | ours | nearest neighbour | ours no worse in | "
             "worst run (ours - nearest) |", "|---|---|---|---|---|---|"]
    for world in dict.fromkeys(r["world"] for r in results):
        for learner, rows in _by(results, world).items():
            ours = np.array([r["same_memory"]["ours"] for r in rows])
            near = np.array([r["same_memory"]["nearest"] for r in rows])
            lines.append(f"| {world} | {learner} | {ours.mean():.4f} | {near.mean():.4f} | "
                         f"{int(np.sum(ours <= near))}/{len(rows)} runs | "
                         f"{np.max(ours - near):+.4f} |")
    return "\n".join(lines)


def probes(results: list[dict]) -> str:
    lines = ["| world | learner | goal attempts gain on memory: noisy (positive in) | "
             "noise-free | explore share | interest real / shuffled | mode-1 goals in "
             "never-reachable space: first / last frame (area) |", "|---|---|---|---|---|---|---|"]
    for world in dict.fromkeys(r["world"] for r in results):
        for learner, rows in _by(results, world).items():
            found = [r["probe"] for r in rows if "probe" in r]
            if not found:
                continue

            def avg(key: str, found: list[dict] = found) -> float:
                values = [p[key] for p in found if key in p]
                return float(np.nanmean(values)) if values else float("nan")

            shares = frame_means(np.array([p["mode1_unreachable_share"] for p in found], float))
            area = found[0]["unreachable_area_share"]
            mode1 = ("no mode 1" if shares is None else
                     f"{shares[0]:.2f} / {shares[-1]:.2f} ({area:.2f})")
            true = avg("true_gain_mean")
            lines.append(
                f"| {world} | {learner} | {avg('gain_mean'):+.4f} "
                f"({avg('gain_positive_share'):.2f}) | "
                + ("n/a" if np.isnan(true) else f"{true:+.4f}") + " | "
                f"{avg('explore_share'):.2f} | {avg('interest_real'):.4f} / "
                f"{avg('interest_shuffled'):.4f} | {mode1} |")
    return "\n".join(lines)


def comparisons(results: list[dict]) -> str:
    from sgim_nodes.analysis.report import pairwise_table

    tables = []
    for world in dict.fromkeys(r["world"] for r in results):
        rows = _by(results, world)
        groups = {lr: [r["final"] for r in rows[lr]] for lr in rows}
        pairs = [(a, b) for a, b in COMPARISONS if a in groups and b in groups]
        tables.append(f"**{world}**\n\n" + pairwise_table(groups, pairs))
    return "\n\n".join(tables)


def make(experiment: Experiment, runs_dir: Path, figures_dir: Path) -> Report:
    results = load_results(experiment, runs_dir)
    kind = experiment.runs.get("goals", "benchmark")
    floors = {w: runner_jobs.floor(w, kind)[0] for w in dict.fromkeys(r["world"]
                                                                      for r in results)}
    eval_every = experiment.runs.get("eval_every", 250)
    report = Report()
    page = experiment.pages[0]
    path = figure(results, floors, eval_every, figures_dir / FIGURE)
    report.figures.append(path)
    report.add(page, "figure", f"![error curves of the learners](figures/{FIGURE})")
    report.add(page, "final-errors", final_errors(results, floors))
    report.add(page, "comparisons", comparisons(results))
    report.add(page, "same-memory", same_memory(results))
    report.add(page, "probes", probes(results))
    seconds = sum(r["seconds"] for r in results)
    report.notes.append(f"{len(results)} runs, {seconds / 3600:.1f} h of run time in all, "
                        f"made on {made_on(r.get('machine') for r in results)}")
    return report
