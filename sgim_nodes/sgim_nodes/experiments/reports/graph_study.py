"""What every report of graph runs needs first: the experiment's runs, each checked to be the
run the experiment's file makes with today's learner."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

from sgim_nodes.analysis.pooling import check_alike, run_fingerprint
from sgim_nodes.analysis.study import Study, group_runs, load_study
from sgim_nodes.experiments.pinned import Experiment


class NotPinned(RuntimeError):
    """The runs folder lacks runs of the experiment, or holds runs of another learner."""


def load(experiment: Experiment, runs_dir: Path) -> Study:
    """The experiment's study: every run it names, finished and made by today's learner."""
    expected = experiment.run_fingerprints()
    study = load_study(runs_dir, warn=lambda message: None)
    found = {run.name: run for run in study.runs}
    missing = sorted(set(expected) - set(found))
    if missing:
        raise NotPinned(f"{runs_dir}: {len(missing)} run(s) of {experiment.name} are not made "
                        f"yet ({', '.join(missing[:5])}{', ...' if len(missing) > 5 else ''}): "
                        "run the experiment first")
    unlike = []
    for name, value in expected.items():
        made = run_fingerprint(found[name])
        if made is None or made.value != value or not found[name].finished:
            unlike.append(name)
    if unlike:
        raise NotPinned(f"{runs_dir}: {', '.join(unlike[:5])}{', ...' if len(unlike) > 5 else ''}"
                        f" are not what {experiment.path.name} makes with today's learner "
                        "(unfinished, or another fingerprint): run the experiment again")
    study.runs = [found[name] for name in expected]  # the pinned runs only, in the file's order
    study.repeated_seeds = group_runs(study.runs, warn=lambda message: None)
    check_alike(study)
    return study


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
    return (f"{len(study.runs)} runs through the graph, {sum(durations) / 3600:.1f} h of run "
            "time in all" + (f", {span / 3600:.1f} h from first start to last end" if span
                             else ""))
