"""SGIM-ACTS against SGIM-D (experiments/active_strategies.yaml, issue 33) as
docs/active_strategies.md's blocks: the final errors, SGIM-ACTS against every other learner
(Holm-corrected), the isolated region, the demonstrations each learner took and the issue's
goal on them, and what SGIM-ACTS chose (reports/acts_choices.py), each goal judged beside
what the runs measured."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import yaml

from sgim_nodes.analysis import figures
from sgim_nodes.analysis.floor import benchmark_floor
from sgim_nodes.analysis.report import (
    StudyNumbers,
    isolated_tests_table,
    num,
    pairwise_markdown,
    pval,
    study_numbers,
    table,
)
from sgim_nodes.analysis.statistics import (
    PairTest,
    compare_groups,
    coverage_tests,
    demonstration_times,
    mean_ci,
)
from sgim_nodes.analysis.study import Study
from sgim_nodes.core.experts import FISHING_EXPERTS
from sgim_nodes.core.learner_registry import SGIM_ACTS, SGIM_D, display_name
from sgim_nodes.experiments import shipped
from sgim_nodes.experiments.pinned import Experiment
from sgim_nodes.experiments.reports import Report, acts_arms, acts_choices
from sgim_nodes.experiments.reports.acts_choices import Verdict
from sgim_nodes.experiments.reports.graph_study import load, run_time_note
from sgim_nodes.experiments.reports.study import own_runs
from sgim_nodes.sweep.sweep_file import RunSpec

ACTS = SGIM_ACTS
DEMONSTRATION_RATIO_GOAL = 0.5
"""Issue 33: SGIM-ACTS no worse than SGIM-D with at most this share of its demonstrations."""
FIGURE = "active_strategies_error_curves.png"


def group_of(learner: str, params: tuple[tuple[str, str], ...]) -> str:
    """A run's group, named as study.group_runs names a setting: 'sgim-d [teacher_turns=...]'."""
    if not params:
        return learner
    return f"{learner} [" + ", ".join(f"{k}={yaml.safe_load(v)}" for k, v in params) + "]"


def label(group: str) -> str:
    """A group as the page names it."""
    _, _, rest = group.partition(" [teacher_turns=")
    if rest:
        return f"{display_name(SGIM_D)}, {rest.rstrip(']').replace(',', ', ')} taking turns"
    if group == SGIM_D:
        return f"{display_name(group)}, one teacher who knows everything"
    return display_name(group)


def regroup(study: Study, experiment: Experiment) -> dict[str, RunSpec]:
    """Name every run's group by its settings in the experiment file; the groups in the file's
    order, each with the settings of its first run. The file, not the metadata's commonest
    values, says which run is which (SGIM-D's two arms have ten runs each, so no value is the
    usual one)."""
    groups: dict[str, RunSpec] = {}
    of = {}
    for spec in experiment.graph_runs:
        of[spec.name] = group_of(spec.learner, spec.params)
        groups.setdefault(of[spec.name], spec)
    for run in study.runs:
        run.group = of[run.name]
    return groups


def by_teacher(study: Study, group: str, spec: RunSpec) -> dict[str, float]:
    """Mean demonstrations per run from each teacher: SGIM-ACTS's by the expert that answered
    (source expert:NAME), SGIM-D's teachers taking turns by whose turn it was (turn k, at
    movement k * P, is teacher k mod n's: core/teacher_turns.py); empty for one teacher."""
    runs = study.runs_of(group)
    turns = dict(spec.params).get("teacher_turns")
    if spec.learner == ACTS:
        known = [s.name for s in FISHING_EXPERTS]
        names = [str(s).removeprefix("expert:") for r in runs for s in r.demo_source]
    elif turns and spec.demonstration_period:
        known = [n.strip() for n in str(yaml.safe_load(turns)).split(",")]
        names = [known[int(m) // spec.demonstration_period % len(known)]
                 for r in runs for m in r.demo_index]
    else:
        return {}
    counted = Counter(names)
    return {n: counted[n] / len(runs) for n in acts_choices.page_order(set(known) | set(names))}


def demonstrations_of(study: Study, group: str) -> list[int]:
    """Per run (seed order), the demonstrations the learner took: every one shown to SGIM-D
    and demonstrations only, SGIM-ACTS's answers that showed what it asked for."""
    return [len(r.demo_index) for r in study.runs_of(group)]


def make(experiment: Experiment, runs_dir: Path, figures_dir: Path) -> Report:
    study = load(experiment, runs_dir)
    specs = regroup(study, experiment)
    groups = list(specs)
    if ACTS not in groups:
        raise ValueError(f"{experiment.path.name} has no {ACTS} runs: nothing to report")
    numbers = study_numbers(study, benchmark_floor())
    report, page = Report(), experiment.pages[0]
    figures_dir.mkdir(parents=True, exist_ok=True)
    curves = {g: numbers.curves[g] for g in groups if g in numbers.curves}
    report.figures.append(figures.plot_error_curves(
        curves, figures_dir / FIGURE, numbers.floor.mean if numbers.floor else None,
        demonstration_times(study)))
    report.add(page, "figure", f"![Error curves of the {len(curves)} learners]"
                               f"(figures/{FIGURE})")
    pairs = [(ACTS, g) for g in groups if g != ACTS]
    tests = {t.b: t for t in compare_groups({g: numbers.finals[g].values for g in groups},
                                            pairs)}
    pond = {t.b: t for t in coverage_tests(numbers.coverage, pairs)}
    demos = {g: demonstrations_of(study, g) for g in groups}
    report.add(page, "comparison", comparison(numbers, groups, tests, pond, demos))
    report.add(page, "error-tests", pairwise_markdown(list(tests.values())))
    report.add(page, "pond-tests", isolated_tests_table(list(pond.values())))
    arms = [g for g in groups if g.partition(" [")[0] == SGIM_D]
    against = {g: demonstration_verdict(numbers, demos, tests[g]) for g in arms}
    taught = {g: by_teacher(study, g, spec) for g, spec in specs.items()}
    report.add(page, "demonstrations", demonstrations(study, groups, demos, taught, against))
    runs, window, last = study.runs_of(ACTS), acts_choices.WINDOW, acts_choices.LAST
    shares = acts_choices.choice_shares(runs, last)
    report.figures.append(acts_choices.draw(runs, figures_dir, window))
    report.add(page, "strategies-figure",
               f"![SGIM-ACTS's strategies and the teachers it asked, per window of {window} "
               f"movements](figures/{acts_choices.FIGURE})")
    report.add(page, "strategies", acts_choices.strategies_table(runs, window))
    report.add(page, "regions", acts_choices.regions_table(runs, last))
    report.add(page, "choices", acts_choices.shares_table(shares, last))
    report.add(page, "choice-modes", acts_choices.modes_table(runs, last))
    acts = acts_arms.arms_of(study, specs, last)
    turns = acts_arms.same_teachers(specs)
    judged: list[Verdict] = []
    if len(acts) > 1 and turns is not None:
        arm_tests = acts_arms.error_tests(numbers, acts, turns)
        report.figures.append(acts_arms.draw(acts, figures_dir, window))
        report.add(page, "arms-figure", f"![Each SGIM-ACTS arm's expert share and rough's "
                                        f"share per window of {window} movements]"
                                        f"(figures/{acts_arms.FIGURE})")
        report.add(page, "arms", acts_arms.arms_table(acts, numbers, arm_tests, demos, last))
        both = [a for a in acts if a.name == acts_arms.BOTH]
        values = {} if not both else acts_arms.choice_values(
            both[0], experiment.graph_runs, shipped.behaviours(experiment), shipped.SHIPPED)
        judged = acts_arms.predictions(acts, arm_tests, demos, turns, values)
        report.add(page, "predictions", acts_arms.predictions_table(judged))
    report.add(page, "goals", goals_table([*against.values(),
                                           *acts_choices.verdicts(shares, last),
                                           *acts_arms.goal_verdicts(acts, judged, last)]))
    durations = [r.duration_s for r in study.runs if r.duration_s]
    report.notes.append(f"{run_time_note(study)} (mean {np.mean(durations):.0f} s per run)"
                        if durations else run_time_note(study))
    return report


def _spread(values: list[int]) -> str:
    if not values:
        return "0"
    return str(values[0]) if min(values) == max(values) else f"{min(values)}-{max(values)}"


def comparison(numbers: StudyNumbers, groups: list[str],
               tests: dict[str, PairTest], pond: dict, demos: dict[str, list[int]]) -> str:
    """Per learner: final error, its difference from SGIM-ACTS, demonstrations, the pond."""
    rows = []
    for g in groups:
        i, cov = numbers.finals[g].interval, numbers.coverage[g]
        t, c = tests.get(g), pond.get(g)
        rows.append([
            f"**{label(g)}**" if g == ACTS else label(g),
            f"{num(i.mean)} [{num(i.low)}, {num(i.high)}]",
            "" if t is None else
            f"{num(t.difference.estimate)} ({'yes' if t.significant else 'no'})",
            _spread(demos[g]),
            f"{own_runs(cov)}/{len(cov.runs)}",
            ", ".join(str(r.own_in_region) for r in cov.runs),
            num(cov.first_movement_median, 0),
            "" if c is None else ("yes" if c.significant else "no")])
    n = len(numbers.finals[ACTS].values)
    return "\n".join(table(
        ["learner", "final error [95 % interval]", "SGIM-ACTS minus it (significant)",
         "demonstrations per run", "runs whose own movements reach the pond",
         "own landings there per run", "first pond landing (median)",
         "pond: differs from SGIM-ACTS (significant)"], rows)) + (
        f"\nFinal error on the benchmark goals at the end of the run, mean and 95 % interval "
        f"over {n} seeds; SGIM-ACTS minus it: the difference of the means (negative: "
        "SGIM-ACTS ends closer), 'significant' when both corrected tests agree (the table "
        "below); the pond: the isolated region, 'own' landings leave out imitations of a "
        "teacher.")


def demonstration_verdict(numbers: StudyNumbers, demos: dict[str, list[int]],
                          test: PairTest) -> Verdict:
    """'No worse than SGIM-D with at most half its demonstrations', against one SGIM-D arm:
    the ratio of the mean demonstrations per run, and the corrected tests of the final error
    (worse: both find SGIM-ACTS significantly farther)."""
    other = test.b
    mine, theirs = float(np.mean(demos[ACTS])), float(np.mean(demos[other]))
    ratio = mine / theirs if theirs else None
    few = None if ratio is None else ratio <= DEMONSTRATION_RATIO_GOAL
    worse = test.significant and test.closer == other
    found = ("SGIM-ACTS significantly closer" if test.significant and test.closer == ACTS
             else "SGIM-ACTS significantly farther" if worse
             else "no significant difference")
    e = test.difference
    measured = (f"{num(mine, 1)} demonstrations per run against {num(theirs, 1)}, a ratio of "
                f"{num(ratio, 2)} ({'within' if few else 'above'} the goal); final error "
                f"{num(numbers.finals[ACTS].interval.mean)} against "
                f"{num(numbers.finals[other].interval.mean)}, difference {num(e.estimate)} "
                f"[{num(e.low)}, {num(e.high)}], Holm-corrected p: Welch "
                f"{pval(test.welch_p_holm)}, Mann-Whitney {pval(test.mann_whitney_p_holm)}: "
                f"{found}")
    met = None if few is None or not test.applicable else (few and not worse)
    return Verdict(f"no worse than {label(other)}, with at most "
                   f"{num(DEMONSTRATION_RATIO_GOAL, 2)} times its demonstrations per run",
                   measured, met)


def demonstrations(study: Study, groups: list[str], demos: dict[str, list[int]],
                   taught: dict[str, dict[str, float]], against: dict[str, Verdict]) -> str:
    """Per learner, the demonstrations each run took, from which teacher (and SGIM-ACTS's
    requests), then the goal against each SGIM-D arm."""
    rows = []
    for g in groups:
        ci = mean_ci(demos[g])
        runs = study.runs_of(g)
        asked = [len(r.ask_index) for r in runs] if g == ACTS else []
        rows.append([label(g), ", ".join(map(str, demos[g])),
                     f"{num(ci.mean, 1)} [{num(ci.low, 1)}, {num(ci.high, 1)}]",
                     ", ".join(f"{t} {num(n, 1)}" for t, n in taught[g].items()),
                     ", ".join(map(str, asked)) if asked else ""])
    out = table(["learner", "demonstrations taken, per seed", "mean [95 % interval]",
                 "from each teacher, mean per run", "requests, per seed"], rows)
    out.append("A demonstration taken: one the learner was shown and used (for SGIM-ACTS, an "
               "answer that showed what the strategy asked for; a request answered 'none "
               "there' costs the request but shows nothing).\n")
    out += [f"- Against **{label(g)}**: {v.measured}. The goal, {v.goal}, is **{v.word}**."
            for g, v in against.items()]
    out.append("\nThe goal counts SGIM-ACTS as worse only when both corrected tests of the "
               "final error find it significantly farther from the benchmark goals (the error "
               "tests above).")
    return "\n".join(out)


def goals_table(judged: list[Verdict]) -> str:
    """The issue's goals, what the runs gave, and whether each is met."""
    rows = [[v.goal[0].upper() + v.goal[1:], v.measured, f"**{v.word}**"] for v in judged]
    return "\n".join(table(["the issue's goal", "what the runs gave", "met?"], rows)).rstrip()
