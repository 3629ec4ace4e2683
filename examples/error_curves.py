"""One figure of a page, drawn from the runs the repository ships: each learner's mean error on
the benchmark goals as it practises, with a 95 % interval over its seeds.

No run is made and no ROS is needed: the run tables under experiments/shipped/ hold every
evaluation of every goal (sgim_nodes.analysis.load_runs reads them into a pandas table).

    python examples/error_curves.py                          # active_strategies -> PNG
    python examples/error_curves.py --experiment study --out study.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from sgim_nodes.analysis import load_runs

REPO = Path(__file__).resolve().parents[1]


def curves(runs) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per group: the evaluation counts, the mean over seeds of each run's mean error there,
    and the half-width of its 95 % interval (normal approximation)."""
    per_run = runs.groupby(["group", "run", "movement"]).distance.mean().reset_index()
    out = {}
    for group, rows in per_run.groupby("group"):
        stats = rows.groupby("movement").distance.agg(["mean", "std", "count"])
        half = 1.96 * stats["std"].fillna(0.0) / np.sqrt(stats["count"])
        out[group] = (stats.index.to_numpy(), stats["mean"].to_numpy(), half.to_numpy())
    return out


def draw(found: dict, path: Path, title: str) -> Path:
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for group, (x, mean, half) in found.items():
        ax.plot(x, mean, label=group)
        ax.fill_between(x, mean - half, mean + half, alpha=0.2)
    ax.set_xlabel("movements")
    ax.set_ylabel("mean distance to the benchmark goals (outcome units)")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--experiment", default="active_strategies",
                   help="a pinned experiment (experiments/NAME.yaml; default %(default)s)")
    p.add_argument("--data", type=Path, default=REPO / "experiments" / "shipped",
                   help="run tables or run folders (default: the shipped ones)")
    p.add_argument("--out", type=Path, default=Path("error_curves.png"),
                   help="the figure to write (default %(default)s)")
    args = p.parse_args(argv)
    from sgim_nodes.experiments.pinned import ExperimentError, find

    try:
        names = find(args.experiment).run_fingerprints()
    except ExperimentError as error:
        p.error(str(error))
    runs = load_runs(args.data, names)
    if runs.empty:
        p.error(f"no run of {args.experiment} in {args.data}: ros_ws/reproduce.sh "
                f"{args.experiment} makes them")
    found = curves(runs)
    draw(found, args.out, f"{args.experiment}: {runs.run.nunique()} of {len(names)} runs")
    for group, (x, mean, half) in found.items():
        print(f"{group}: {mean[-1]:.3f} +/- {half[-1]:.3f} at {x[-1]} movements")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
