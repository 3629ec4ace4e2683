"""What every report of graph runs needs first: the experiment's runs, each checked to be the
run the experiment's file makes with today's learner."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

from sgim_nodes.analysis.pooling import check_alike
from sgim_nodes.analysis.study import Study, group_runs, load_study
from sgim_nodes.experiments.pinned import Experiment
from sgim_nodes.provenance.record import made_on


class NotPinned(RuntimeError):
    """The runs folder lacks runs of the experiment, or holds runs of another learner."""


def load(experiment: Experiment, runs_dir: Path) -> Study:
    """The experiment's study: every run it names, finished and made by today's learner, from
    the runs folder, else from the run tables the repository ships (experiments/shipped.py)."""
    from sgim_nodes.experiments.shipped import SHIPPED, shipped_runs, todays_runs

    expected = experiment.run_fingerprints()
    made = load_study(runs_dir, warn=lambda message: None).runs if runs_dir.is_dir() else []
    found = {run.name: run for run in todays_runs(experiment, made)}
    if len(found) < len(expected):
        for name, run in shipped_runs(experiment).items():
            found.setdefault(name, run)
    missing = [name for name in expected if name not in found]
    if missing:
        unlike = sorted({run.name for run in made} & set(missing))
        absent = [name for name in missing if name not in unlike]
        said = []
        if absent:
            said.append(f"{len(absent)} run(s) of {experiment.name} are not made yet "
                        f"({_some(absent)})")
        if unlike:
            said.append(f"{_some(unlike)} are not what {experiment.path.name} makes with "
                        "today's learner (unfinished, or another fingerprint)")
        raise NotPinned(f"{runs_dir} and {SHIPPED.relative_to(SHIPPED.parents[1])}/: "
                        + "; ".join(said) + ": run the experiment")
    study = Study(runs_dir, [found[name] for name in expected], {}, [])  # the file's order
    study.repeated_seeds = group_runs(study.runs, warn=lambda message: None)
    check_alike(study)
    return study


def _some(names: list[str]) -> str:
    return ", ".join(names[:5]) + (", ..." if len(names) > 5 else "")


def shipped_count(study: Study) -> int:
    """How many of the study's runs were read from shipped run tables."""
    from sgim_nodes.experiments.shipped import SUFFIX

    return sum(run.path.suffix == SUFFIX for run in study.runs)


def wall_span(study: Study) -> float | None:
    """Seconds from the first run's start to the last run's end, from their metadata; None
    when a run does not say (the report may be made long after the runs)."""
    try:
        starts = [datetime.fromisoformat(r.metadata["started"]) for r in study.runs]
        ends = [datetime.fromisoformat(r.metadata["ended"]) for r in study.runs]
    except (KeyError, TypeError, ValueError):
        return None
    return (max(ends) - min(starts)).total_seconds() if starts else None


def run_time_note(study: Study) -> str:
    """The provenance note of a graph experiment's runs: how many, their run time and the
    span they were made in (the report itself may be made again in seconds)."""
    durations = [r.duration_s for r in study.runs if r.duration_s]
    span = wall_span(study)
    shipped = shipped_count(study)
    return (f"{len(study.runs)} runs through the graph, {sum(durations) / 3600:.1f} h of run "
            "time in all" + (f", {span / 3600:.1f} h from first start to last end" if span
                             else "")
            + f", made on {made_on(r.metadata.get('machine') for r in study.runs)}"
            + (f"; {shipped} read from the run tables of experiments/shipped/" if shipped
               else ""))
