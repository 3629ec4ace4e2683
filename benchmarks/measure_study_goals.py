"""Per-goal final errors of a study, split by how far each benchmark goal lies from the teacher's
demonstrated outcomes (and whether it lies in the isolated region).

Why: demonstrations only can only be as good as the demonstrated points it imitates; a learner
that explores by itself should win where the teacher showed nothing. This separates the two,
from the bags alone (each run's last evaluation holds every goal's distance).

    PYTHONPATH=sim_bridge:sgim_nodes .venv/bin/python benchmarks/measure_study_goals.py \
        runs/study [--near 0.1]
"""

from __future__ import annotations

import argparse
import re
import sys
import warnings
from pathlib import Path

import numpy as np
from scipy import stats

from sgim_nodes.bag.run_folder import load_run_folder
from sim_bridge.data_files import load_benchmark_goals, load_teaching_set
from sim_bridge.lake import ISOLATED_REGION

RUN_NAME = re.compile(r"^(?P<learner>.+)-seed(?P<seed>\d+)$")


def final_distances(run_dir: Path, goals: np.ndarray) -> np.ndarray | None:
    """The last evaluation's per-goal distances, in the benchmark's goal order."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        evaluations = load_run_folder(run_dir, topics=["evaluations"]).evaluations
    if not evaluations:
        return None
    last = evaluations[-1]
    if last.goals.shape != goals.shape or not np.allclose(last.goals, goals, atol=1e-6):
        raise SystemExit(f"{run_dir}: its evaluation goals are not the shipped benchmark set")
    return last.distances


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study", type=Path, help="the study folder (<learner>-seed<N>/ runs)")
    parser.add_argument("--near", type=float, default=0.1,
                        help="a goal is 'near a demonstration' within this distance of a "
                             "demonstrated outcome (outcome units; default 0.1)")
    args = parser.parse_args(argv)
    if not args.study.is_dir():
        parser.error(f"{args.study} is not a folder")
    goals = load_benchmark_goals()
    taught = load_teaching_set().outcomes
    to_demo = np.linalg.norm(goals[:, None, :] - taught[None, :, :], axis=2).min(axis=1)
    isolated = np.linalg.norm(goals - np.asarray(ISOLATED_REGION["centre"]), axis=1) \
        <= ISOLATED_REGION["radius"]
    near = (to_demo < args.near) & ~isolated
    far = (to_demo >= args.near) & ~isolated
    print(f"{len(goals)} goals: {near.sum()} within {args.near} of a demonstrated outcome, "
          f"{far.sum()} farther, {isolated.sum()} in the isolated region "
          f"(median distance to a demonstration {np.median(to_demo):.3f})")
    per_learner: dict[str, list[np.ndarray]] = {}
    for run in sorted(p for p in args.study.iterdir() if p.is_dir()):
        match = RUN_NAME.match(run.name)
        if not match:
            continue
        d = final_distances(run, goals)
        if d is not None:
            per_learner.setdefault(match["learner"], []).append(d)
    print(f"{'learner':14s} {'runs':>4s} {'near':>7s} {'far':>7s} {'isolated':>8s} {'all':>7s}"
          "   (mean final distance over runs; far: per run)")
    for learner, runs in per_learner.items():
        d = np.array(runs)
        row = [d[:, near].mean(), d[:, far].mean(), d[:, isolated].mean(), d.mean()]
        far_runs = ", ".join(f"{x:.3f}" for x in d[:, far].mean(axis=1))
        print(f"{learner:14s} {len(d):4d} " + " ".join(f"{x:7.3f}" for x in row[:2])
              + f" {row[2]:8.3f} {row[3]:7.3f}   far: {far_runs}")
    reference = "sgim-d"
    if reference in per_learner and len(per_learner[reference]) > 1:
        print(f"{reference} against each learner, per-run means of each goal group "
              "(two-sided Welch p / Mann-Whitney p):")
        mine = np.array(per_learner[reference])
        for learner, runs in per_learner.items():
            other = np.array(runs)
            if learner == reference or len(other) < 2:
                continue
            cells = []
            for name, subset in (("near", near), ("far", far), ("isolated", isolated)):
                a, b = mine[:, subset].mean(axis=1), other[:, subset].mean(axis=1)
                welch = stats.ttest_ind(a, b, equal_var=False).pvalue
                mwu = stats.mannwhitneyu(a, b, alternative="two-sided").pvalue
                cells.append(f"{name} {a.mean() - b.mean():+.3f} (p {welch:.2g} / {mwu:.2g})")
            print(f"  vs {learner:12s} " + "; ".join(cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())
