"""The social modes (experiments/social_modes.yaml) as docs/social_modes.md's blocks: every
setting against the paper's SGIM-D, on the final error and on the isolated region."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sgim_nodes.analysis import figures
from sgim_nodes.analysis.floor import benchmark_floor
from sgim_nodes.analysis.report import (
    isolated_tests_table,
    num,
    pairwise_markdown,
    study_numbers,
    table,
)
from sgim_nodes.analysis.statistics import compare_groups, coverage_tests, demonstration_times
from sgim_nodes.core.learner_registry import SGIM_D, display_name, learner_names
from sgim_nodes.experiments.pinned import Experiment
from sgim_nodes.experiments.reports import Report
from sgim_nodes.experiments.reports.graph_study import load, run_time_note
from sgim_nodes.experiments.reports.study import own_runs

PAPER = SGIM_D
"""The group of the paper's SGIM-D (means and goal, random-unreached, periodic, P = 150): the
setting every block of the sweep varies one choice around."""
FIGURE = "social_modes_error_curves.png"


def label(group: str) -> str:
    """A group as the page names it: 'sgim-d [demonstration_period=500]' -> 'P = 500'."""
    if group == PAPER:
        return f"{display_name(group)}, the paper's"
    if group in learner_names():
        return display_name(group)
    inside = group[group.find("[") + 1:group.rfind("]")]
    parts = []
    for item in inside.split(", "):
        key, _, value = item.partition("=")
        parts.append({"demonstration_period": f"P = {value}",
                      "demonstration_content": f"content `{value}`",
                      "teacher_choice": f"choice `{value}`",
                      "timing": f"timing `{value}`"}.get(key, item))
    return ", ".join(parts)


def make(experiment: Experiment, runs_dir: Path, figures_dir: Path) -> Report:
    study = load(experiment, runs_dir)
    numbers = study_numbers(study, benchmark_floor())
    groups = list(numbers.finals)
    others = [g for g in groups if g != PAPER]
    report = Report()
    page = experiment.pages[0]
    figures_dir.mkdir(parents=True, exist_ok=True)
    path = figures.plot_error_curves(numbers.curves, figures_dir / FIGURE,
                                     numbers.floor.mean if numbers.floor else None,
                                     demonstration_times(study))
    report.figures.append(path)
    report.add(page, "figure", f"![Error curves of the {len(groups)} settings](figures/{FIGURE})")
    tests = {t.b: t for t in compare_groups({g: numbers.finals[g].values for g in groups},
                                            [(PAPER, g) for g in others])}
    pond = {t.b: t for t in coverage_tests(numbers.coverage, [(PAPER, g) for g in others])}
    rows = []
    for g in groups:
        i, cov = numbers.finals[g].interval, numbers.coverage[g]
        t, c = tests.get(g), pond.get(g)
        demos = numbers.summaries[g].demonstrations
        rows.append([
            f"**{label(g)}**" if g == PAPER else label(g),
            f"{num(i.mean)} [{num(i.low)}, {num(i.high)}]",
            "" if t is None else
            f"{num(t.difference.estimate)} ({'yes' if t.significant else 'no'})",
            f"{own_runs(cov)}/{len(cov.runs)}",
            ", ".join(str(r.own_in_region) for r in cov.runs),
            num(cov.first_movement_median, 0),
            "" if c is None else ("yes" if c.significant else "no"),
            "0" if not demos else (f"{min(demos)}-{max(demos)}" if min(demos) != max(demos)
                                   else str(demos[0]))])
    n = len(numbers.finals[PAPER].values)
    comparison = "\n".join(table(
        ["setting", "final error [95 % interval]", "against the paper's SGIM-D (significant)",
         "runs whose own movements reach the pond", "own landings there per run",
         "first pond landing (median)", "pond: differs (significant)",
         "demonstrations per run"], rows)) + (
        f"\n\nFinal error on the benchmark goals at the end of the run, mean and 95 % interval "
        f"over {n} seeds; against the paper's SGIM-D: the difference of the means, "
        "'significant' when both corrected tests agree (the table below); the pond: the "
        "isolated region, 'own' landings leave out imitations of the teacher.")
    report.add(page, "comparison", comparison)
    report.add(page, "error-tests", pairwise_markdown(list(tests.values())))
    report.add(page, "pond-tests", isolated_tests_table(list(pond.values())))
    durations = [r.duration_s for r in study.runs if r.duration_s]
    report.notes.append(f"{run_time_note(study)} (mean {np.mean(durations):.0f} s per run)")
    return report
