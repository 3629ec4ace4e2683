"""The paper's study (experiments/study.yaml) as docs/results.md's blocks and the README's
summary: the tables of `analyze`, its figures, where each learner is good, the paper's three
findings checked against the runs, and what the study cost."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sgim_nodes.analysis import figures
from sgim_nodes.analysis.floor import benchmark_floor
from sgim_nodes.analysis.report import (
    StudyNumbers,
    num,
    pairwise_markdown,
    pval,
    render,
    study_numbers,
    table,
)
from sgim_nodes.analysis.statistics import (
    ALPHA,
    PairTest,
    compare_groups,
    demonstration_times,
    find_test,
)
from sgim_nodes.analysis.study import RunData, Study
from sgim_nodes.core.learner_registry import DEMO_ONLY, RANDOM, SAGGRIAC, SGIM_D, display_name
from sgim_nodes.experiments.pinned import Experiment
from sgim_nodes.experiments.reports import Report, second_finding
from sgim_nodes.experiments.reports.graph_study import load, run_time_note, wall_span

NEAR = 0.1
"""A benchmark goal is near a demonstration within this distance (outcome units) of a
demonstrated outcome: about 1.4 noise units, chosen before the first study was looked at."""
FRAMES = (1000, 2500, 5000)  # the paper's landing frames


def make(experiment: Experiment, runs_dir: Path, figures_dir: Path) -> Report:
    study = load(experiment, runs_dir)
    numbers = study_numbers(study, benchmark_floor())
    report = Report()
    page, readme = experiment.pages
    for name, text in render(numbers).items():
        report.add(page, name, text)
    report.figures += draw(study, numbers, figures_dir)
    groups = goal_groups(study)
    report.add(page, "goal-groups", groups.text)
    report.add(page, "findings", findings(numbers, groups.values))
    report.add(page, "second-finding", second_finding.block(numbers, groups))
    report.add(page, "cost", cost(study))
    report.add(readme, "summary", summary(numbers))
    report.notes.append(run_time_note(study))
    return report


def draw(study: Study, numbers: StudyNumbers, folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    floor = numbers.floor.mean if numbers.floor else None
    drawn = [figures.plot_error_curves(numbers.curves, folder / "study_error_curves.png", floor,
                                       demonstration_times(study)),
             figures.plot_landings(study, FRAMES, folder / "study_landings.png"),
             figures.plot_landings(study, FRAMES, folder / "study_landings_frames.png",
                                   cumulative=False)]
    tree = figures.plot_region_trees(study, FRAMES, folder / "study_region_tree.png")
    return [*drawn, *([tree] if tree is not None else [])]


def _final_distances(run: RunData, goals: np.ndarray) -> np.ndarray | None:
    """The run's last evaluation, goal by goal, in the benchmark's order."""
    if not len(run.eval_distances):
        return None
    if run.eval_goals.shape != goals.shape or not np.allclose(run.eval_goals, goals, atol=1e-9):
        raise ValueError(f"{run.name}: its evaluation goals are not the shipped benchmark set")
    return np.asarray(run.eval_distances[-1], float)


@dataclass(frozen=True)
class GoalGroups:
    """Each group's mean final distance per learner (runs in seed order, with their seeds),
    the goals of each group, and SGIM-D against each learner group by group, corrected."""

    values: dict[str, dict[str, list[float]]]
    seeds: dict[str, list[int]]
    masks: dict[str, np.ndarray]
    tests: list[PairTest]
    text: str


def goal_masks() -> dict[str, np.ndarray]:
    """The benchmark goals near a demonstrated outcome, farther, in the isolated region, all."""
    from sim_bridge.data_files import load_benchmark_goals, load_teaching_set
    from sim_bridge.lake import ISOLATED_REGION

    goals = np.asarray(load_benchmark_goals(), float)
    taught = np.asarray(load_teaching_set().outcomes, float)
    to_demo = np.sqrt(((goals[:, None, :] - taught[None, :, :]) ** 2).sum(-1)).min(1)
    pond = np.sqrt(((goals - np.asarray(ISOLATED_REGION["centre"])) ** 2).sum(-1)) \
        <= ISOLATED_REGION["radius"]
    return {"near": (to_demo < NEAR) & ~pond, "far": (to_demo >= NEAR) & ~pond,
            "pond": pond, "all": np.ones(len(goals), bool)}


def goal_groups(study: Study) -> GoalGroups:
    """Each run's final error on the goals near a demonstrated outcome, farther, and in the
    isolated region; SGIM-D against every other learner on each, Holm-corrected together."""
    from sim_bridge.data_files import load_benchmark_goals

    goals = np.asarray(load_benchmark_goals(), float)
    subsets = goal_masks()
    groups: dict[str, dict[str, list[float]]] = {name: {} for name in subsets}
    seeds: dict[str, list[int]] = {}
    for learner in study.learners:
        for run in study.runs_of(learner):
            d = _final_distances(run, goals)
            if d is not None:
                seeds.setdefault(learner, []).append(run.seed)
                for name, mask in subsets.items():
                    groups[name].setdefault(learner, []).append(float(d[mask].mean()))
    rows = []
    for learner in study.learners:
        cells = [num(float(np.mean(groups[g][learner]))) if groups[g].get(learner) else "n/a"
                 for g in subsets]
        rows.append([display_name(learner), *cells])
    sizes = {g: int(m.sum()) for g, m in subsets.items()}
    head = table(["learner", f"{sizes['near']} goals within {NEAR} of a demonstration",
                  f"{sizes['far']} goals farther", f"{sizes['pond']} goals in the isolated "
                  "region", f"all {sizes['all']}"], rows)
    labelled = {f"{learner} ({g})": values for g in ("near", "far", "pond")
                for learner, values in groups[g].items()}
    pairs = [(f"{SGIM_D} ({g})", f"{other} ({g})") for g in ("near", "far", "pond")
             for other in study.learners if other != SGIM_D and SGIM_D in groups[g]]
    tests = compare_groups(labelled, pairs)
    text = "\n".join(head) + (
        f"\n\nMean over runs of each run's mean final distance on the goals of the group "
        f"(goals split by their distance to the nearest demonstrated outcome of the teaching "
        f"set; the split at {NEAR} was chosen before the first study was looked at).\n\n"
        "SGIM-D against each learner, group by group:\n\n" + pairwise_markdown(tests))
    return GoalGroups(groups, seeds, subsets, tests, text)


def _mean(numbers: StudyNumbers, learner: str) -> float:
    return numbers.finals[learner].interval.mean


def _verdict(numbers: StudyNumbers, a: str, b: str) -> str:
    """'a ends closer than b' checked: the means, the corrected p-values and the verdict."""
    t = find_test(numbers.tests, a, b)
    if t is None:
        return f"{display_name(a)} or {display_name(b)} is missing"
    ma, mb = _mean(numbers, a), _mean(numbers, b)
    holds = t.significant and t.closer == a
    word = ("reproduced" if holds else "not reproduced: the reverse" if t.significant
            else "not reproduced: no significant difference")
    return (f"{display_name(a)} {num(ma)} against {display_name(b)} {num(mb)} "
            f"(Holm-corrected p: Welch {pval(t.welch_p_holm)}, "
            f"Mann-Whitney {pval(t.mann_whitney_p_holm)}): **{word}**")


def findings(numbers: StudyNumbers, groups: dict[str, dict[str, list[float]]]) -> str:
    """The paper's findings, each checked against the runs (significance at ALPHA, corrected
    over the pairwise table)."""
    from sgim_nodes.analysis.statistics import compare

    lines = ["1. *SGIM-D ends closer to the benchmark goals than SAGG-RIAC and random actions.* "
             + _verdict(numbers, SGIM_D, SAGGRIAC) + "; "
             + _verdict(numbers, SGIM_D, RANDOM) + ".",
             "2. *SGIM-D ends closer than demonstrations only.* Over all goals: "
             + _verdict(numbers, SGIM_D, DEMO_ONLY) + "."]
    far = groups["far"]
    if SGIM_D in far and DEMO_ONLY in far:
        t = compare(SGIM_D, far[SGIM_D], DEMO_ONLY, far[DEMO_ONLY])
        side = display_name(SGIM_D if t.closer == SGIM_D else DEMO_ONLY)
        lines[-1] += (f" On the goals far from every demonstration: SGIM-D "
                      f"{num(float(np.mean(far[SGIM_D])))} against "
                      f"{num(float(np.mean(far[DEMO_ONLY])))}, {side} closer (p: Welch "
                      f"{pval(t.welch_p)}, Mann-Whitney {pval(t.mann_whitney_p)}; the goal "
                      "groups' table corrects it with the others).")
    cov = numbers.coverage
    if SGIM_D in cov:
        reached = {k: f"{own_runs(c)}/{len(c.runs)}" for k, c in cov.items()}
        others = [t for t in numbers.region_tests if SGIM_D in (t.a, t.b)]
        beaten = [t.b if t.a == SGIM_D else t.a for t in others if t.significant]
        lines.append(
            "3. *SGIM-D alone explores the isolated region.* Runs whose own movements land "
            "there: " + ", ".join(f"{display_name(k)} {v}" for k, v in reached.items())
            + ". SGIM-D's own coverage differs significantly (corrected) from: "
            + (", ".join(display_name(b) for b in beaten) or "none") + ".")
    lines.append(f"\nSignificance: both corrected p-values below {ALPHA} (the pairwise table); "
                 "the verdicts are the tool's, from the tables above.")
    return "\n".join(lines)


def own_runs(coverage) -> int:
    """Runs whose own movements (not imitations of the teacher) landed in the pond."""
    return sum(r.own_in_region > 0 for r in coverage.runs)


def cost(study: Study) -> str:
    rows = []
    for learner in study.learners:
        d = [r.duration_s for r in study.runs_of(learner) if r.duration_s]
        if d:
            rows.append([display_name(learner), str(len(d)),
                         f"{np.mean(d):.0f}", f"{min(d):.0f}-{max(d):.0f}"])
    total = sum(r.duration_s or 0.0 for r in study.runs)
    span = wall_span(study)
    made_in = (f", made in {span / 3600:.1f} h of wall time (the first run's start to the last "
               "run's end)" if span else "")
    return "\n".join(table(["learner", "runs", "mean run time (s)", "range (s)"], rows)) + (
        f"\n\n{total / 3600:.1f} h of run time in all{made_in}, on the machine and cores of "
        "the provenance block at the top.")


def summary(numbers: StudyNumbers) -> str:
    rows = []
    for learner, final in numbers.finals.items():
        i = final.interval
        demos = numbers.summaries[learner].demonstrations if learner in numbers.summaries \
            else None
        shown = "0" if not demos else (f"{min(demos)}-{max(demos)}" if min(demos) != max(demos)
                                       else str(demos[0]))
        cov = numbers.coverage.get(learner)
        rows.append([display_name(learner), f"{num(i.mean)} [{num(i.low)}, {num(i.high)}]",
                     shown, f"{own_runs(cov)}/{len(cov.runs)}" if cov else "n/a"])
    floor = numbers.floor
    out = table(["learner", "final error [95 % interval]", "demonstrations per run",
                 "runs whose own movements reach the isolated pond"], rows)
    if floor is not None and math.isfinite(floor.mean):
        out.append(f"Floor (the best a lookup on a dense map of the world does): "
                   f"{num(floor.mean)}.")
    return "\n".join(out)
