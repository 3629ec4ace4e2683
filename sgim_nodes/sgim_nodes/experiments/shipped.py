"""The runs the repository ships: one run table per graph run (analysis/run_table.py), kept in
experiments/shipped/ and valid while today's code makes the same run.

Why: the pages' runs cost much compute and live in a runs folder no clone has. A run
table is the part of a run the pages read (no bag), so a fresh clone makes every page from
the shipped tables without making a run, and runs made in one place (or one
session) are never made again while the code behaves the same.

When is a shipped run today's run? Each table is stamped with its run's behaviour
(references.run_behaviours): the reference digest of its configuration and the data files.
While the reference runs of today's code give the same digest, the run it stands for would
move the same, so a refactor that changes no movement keeps every table; one that changes a
configuration's movements drops that configuration's tables until its runs are made again.
A run shared by two experiments (same name, same configuration) is one table.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

from sgim_nodes.analysis.pooling import run_fingerprint
from sgim_nodes.analysis.run_table import RunTableError, load_run, read_stamp, save_run
from sgim_nodes.analysis.study import RunData
from sgim_nodes.experiments.makers import result_fingerprint
from sgim_nodes.experiments.pinned import REPO, Experiment
from sgim_nodes.experiments.references import ReferencesOutdated, read_table, run_behaviours

SHIPPED = REPO / "experiments" / "shipped"
SUFFIX = ".npz"


def table_path(name: str, folder: Path | None = None) -> Path:
    """Where the run called `name` is shipped."""
    return (folder or SHIPPED) / f"{name}{SUFFIX}"


def behaviours(experiment: Experiment) -> dict[str, str]:
    """Run name -> today's behaviour of that run; empty when the kept references are not
    today's code's (then no shipped run can be trusted, nor shipped)."""
    try:
        return run_behaviours(experiment, read_table(experiment.references_path))
    except ReferencesOutdated:
        return {}


def todays_tables(experiment: Experiment, folder: Path | None = None,
                  warn: Callable[[str], None] = lambda message: None) -> dict[str, Path]:
    """The experiment's run tables stamped with today's behaviour, by run name (stamps only:
    no column is read)."""
    found: dict[str, Path] = {}
    for name, behaviour in behaviours(experiment).items():
        path = table_path(name, folder)
        if not path.is_file():
            continue
        try:
            if read_stamp(path).get("behaviour") == behaviour:
                found[name] = path
            else:
                warn(f"{path.name}: made by code that moved otherwise: not used")
        except (OSError, ValueError, KeyError, RunTableError) as error:
            warn(f"{path.name}: unreadable ({error}): not used")
    return found


def shipped_runs(experiment: Experiment, folder: Path | None = None,
                 warn: Callable[[str], None] = lambda message: None) -> dict[str, RunData]:
    """The experiment's runs the repository ships with today's behaviour, by name."""
    found: dict[str, RunData] = {}
    for name, path in todays_tables(experiment, folder, warn).items():
        try:
            found[name] = load_run(path)
        except (OSError, ValueError, KeyError, RunTableError) as error:
            warn(f"{path.name}: unreadable ({error}): not used")
    return found


def todays_runs(experiment: Experiment, runs: Iterable[RunData]) -> list[RunData]:
    """The runs made by today's code for the experiment: finished, named by it, and of the
    learner fingerprint it gives that name."""
    expected = experiment.run_fingerprints()
    kept = []
    for run in runs:
        made = run_fingerprint(run)
        if run.finished and made is not None and expected.get(run.name) == made.value:
            kept.append(run)
    return kept


def ship(experiment: Experiment, runs: Iterable[RunData], folder: Path | None = None
         ) -> list[Path]:
    """Write a table for each of `runs` made by today's code (todays_runs), stamped with its
    behaviour; the paths written. Nothing is shipped when the references are outdated."""
    today: Mapping[str, str] = behaviours(experiment)
    if not today:
        return []
    return [save_run(run, table_path(run.name, folder), {"behaviour": today[run.name]})
            for run in todays_runs(experiment, runs)]


def ship_folder(experiment: Experiment, runs_dir: Path, folder: Path | None = None
                ) -> list[Path]:
    """Ship every finished run of the experiment that `runs_dir` holds made by today's code."""
    from sgim_nodes.analysis.study import load_study

    if experiment.maker != "graph" or not runs_dir.is_dir():
        return []
    return ship(experiment, load_study(runs_dir, warn=lambda message: None).runs, folder)


# --- runner and world experiments: their result files ---------------------------------------

STAMPS = "stamps.yaml"
"""Beside a runner or world experiment's shipped result files: job name -> its behaviour."""


def results_folder(experiment: Experiment, folder: Path | None = None) -> Path:
    """Where a runner or world experiment's result files are shipped (one folder each: their
    job names are the experiment's own)."""
    return (folder or SHIPPED) / experiment.name


def file_jobs(experiment: Experiment) -> tuple[Sequence[Any], ModuleType]:
    """A runner or world experiment's jobs and the module that makes and reads their result
    files."""
    from sgim_nodes.experiments import runner_jobs, world_jobs

    if experiment.maker == "runner":
        return experiment.runner_jobs, runner_jobs
    return experiment.world_jobs, world_jobs


def _stamps(folder: Path) -> dict[str, str]:
    import yaml

    try:
        found = yaml.safe_load((folder / STAMPS).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return {str(k): str(v) for k, v in found.items()} if isinstance(found, dict) else {}


def ship_results(experiment: Experiment, runs_dir: Path, folder: Path | None = None
                 ) -> list[Path]:
    """Copy each result file `runs_dir` holds made by today's code into the experiment's
    shipped folder, its behaviour in the folder's stamps; the paths written."""
    import yaml

    today = behaviours(experiment)
    if not today or not runs_dir.is_dir():
        return []
    jobs, module = file_jobs(experiment)
    target = results_folder(experiment, folder)
    stamps, written = _stamps(target), []
    for job in jobs:
        made = module.result_path(runs_dir, job)
        found = module.read_result(made) if made.is_file() else None
        if found is None or result_fingerprint(found)[0] != job.fingerprint().value:
            continue
        target.mkdir(parents=True, exist_ok=True)
        path = target / made.name
        if not path.is_file() or path.read_bytes() != made.read_bytes():
            tmp = path.with_name(f".{path.name}.tmp")
            tmp.write_bytes(made.read_bytes())
            tmp.replace(path)
        stamps[job.name] = today[job.name]
        written.append(path)
    if written:
        (target / STAMPS).write_text(yaml.safe_dump(dict(sorted(stamps.items()))),
                                     encoding="utf-8")
    return written


def read_result(experiment: Experiment, runs_dir: Path, job) -> dict | None:
    """A runner or world job's result: from the runs folder, else from the shipped file whose
    stamp is today's behaviour; None when neither has it."""
    _, module = file_jobs(experiment)
    made = module.result_path(runs_dir, job)
    found = module.read_result(made) if made.is_file() else None
    if found is not None:
        return found
    target = results_folder(experiment)
    if _stamps(target).get(job.name) != behaviours(experiment).get(job.name):
        return None
    path = target / made.name
    return module.read_result(path) if path.is_file() else None


def shipped_names(experiment: Experiment) -> set[str]:
    """The runs or jobs of the experiment shipped with today's behaviour (stamps only: no
    column is read), which need not be made again."""
    if experiment.maker == "graph":
        return set(todays_tables(experiment))
    today = behaviours(experiment)
    jobs, module = file_jobs(experiment)
    target = results_folder(experiment)
    stamps = _stamps(target)
    return {job.name for job in jobs if job.name in today and stamps.get(job.name) ==
            today[job.name] and (target / module.result_path(target, job).name).is_file()}
