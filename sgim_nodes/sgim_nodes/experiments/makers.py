"""Make an experiment's runs: resumable, here (several side by side) or on a Ray cluster.

Graph runs go through the sweep driver (sweep/driver.py), which makes each one a Ray task and
resumes by the runs' fingerprints; a run another experiment already made, with the same name
and learner fingerprint, is linked rather than made again (the paper's default SGIM-D is in the
study and in the social modes). Runner and world runs are one result file each, made by a
process pool here or by Ray's pool on a cluster, and skipped when a file of today's
fingerprint is there; a file of another learner is moved to ``.unlike/`` and made again.
"""

from __future__ import annotations

import os
import shutil
import sys
import time
from collections.abc import Callable, Collection, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path
from types import ModuleType
from typing import Any

from sgim_nodes.experiments.pinned import Experiment, runs_root
from sgim_nodes.provenance.fingerprint import Fingerprint
from sgim_nodes.provenance.record import machine

UNLIKE_DIR = ".unlike"


def say(message: str) -> None:
    print(f"[reproduce] {message}", file=sys.stderr, flush=True)


def make_runs(experiment: Experiment, runs_dir: Path, parallel: int, address: str | None,
              keep_unlike: bool, skip: Collection[str] = ()) -> int:
    """Make what is missing, but the runs or jobs named in `skip`; 0 when every run is
    there."""
    runs_dir.mkdir(parents=True, exist_ok=True)
    if experiment.maker == "graph":
        runs = tuple(s for s in experiment.graph_runs if s.name not in skip)
        return _graph(experiment, runs, runs_dir, parallel, address, keep_unlike)
    from sgim_nodes.experiments import runner_jobs, world_jobs

    module = runner_jobs if experiment.maker == "runner" else world_jobs
    jobs = experiment.runner_jobs if experiment.maker == "runner" else experiment.world_jobs
    jobs = [job for job in jobs if job.name not in skip]
    return make_file_jobs(jobs, module, runs_dir, parallel, address, keep_unlike)


def _graph(experiment: Experiment, runs: tuple, runs_dir: Path, parallel: int,
           address: str | None, keep_unlike: bool) -> int:
    from sgim_nodes.sweep import driver
    from sgim_nodes.sweep.sweep_file import Sweep

    if not runs:
        return 0
    sweep = Sweep(experiment.path, experiment.name, runs_dir.absolute(),
                  experiment.run_timeout, runs)
    # Siblings are where experiments' runs go, and beside a --runs-dir chosen elsewhere.
    roots = list(dict.fromkeys((runs_root().absolute(), runs_dir.absolute().parent)))
    linked = link_finished_elsewhere(sweep, roots)
    if linked:
        say(f"{len(linked)} run(s) taken from other experiments, made by the same learner: "
            + ", ".join(linked))
    argv = [str(experiment.path), "--runs-dir", str(runs_dir), "--parallel", str(parallel)]
    argv += ["--address", address] if address else []
    argv += ["--keep-unlike"] if keep_unlike else []
    return driver.drive(sweep, driver.parse_args(argv))


def link_finished_elsewhere(sweep, roots: Sequence[Path]) -> list[str]:
    """Hard-link into the sweep's folder every absent run that a sibling experiment's folder
    (a folder in one of `roots`) holds finished, with the same name and today's fingerprint."""
    from sgim_nodes.sweep import results
    from sgim_nodes.sweep.results import State

    linked = []
    siblings = [p for root in roots if root.is_dir() for p in sorted(root.iterdir())
                if p.is_dir() and p.absolute() != sweep.runs_dir.absolute()]
    for spec in sweep.runs:
        target = sweep.runs_dir / spec.name
        if target.exists():
            continue
        for sibling in siblings:
            source = sibling / spec.name
            if (source.is_dir()
                    and results.run_state(source, spec).state is State.FINISHED):
                work = sweep.runs_dir / f".{spec.name}.linking"
                shutil.rmtree(work, ignore_errors=True)
                shutil.copytree(source, work, copy_function=os.link,
                                ignore=shutil.ignore_patterns("analysis_cache.npz"))
                work.rename(target)
                linked.append(f"{spec.name} ({sibling.name})")
                break
    return linked


def result_fingerprint(result: dict[str, Any]) -> tuple[str, Fingerprint | None]:
    """The fingerprint a result file records: its value ('' when none) and, for a runner's
    (a mapping), the fingerprint itself."""
    made = result.get("fingerprint")
    if isinstance(made, dict):
        found = Fingerprint.from_dict(made)
        return (found.value if found else ""), found
    return str(made or ""), None


def make_file_jobs(jobs: Sequence[Any], module: ModuleType, runs_dir: Path, parallel: int,
                   address: str | None, keep_unlike: bool) -> int:
    """Run every job whose result file is missing or of another learner; 1 if any failed."""
    todo = []
    for job in jobs:
        path = module.result_path(runs_dir, job)
        found = module.read_result(path) if path.exists() else None
        if found is None:
            todo.append(job)
            continue
        value, recorded = result_fingerprint(found)
        expected = job.fingerprint()
        if value == expected.value:
            continue
        why = ", ".join(recorded.differences(expected)) if recorded else "fingerprint"
        if keep_unlike:
            say(f"{job.name}: its learner differs from this checkout's ({why}); kept "
                "(--keep-unlike)")
            continue
        aside = runs_dir / UNLIKE_DIR
        aside.mkdir(exist_ok=True)
        path.rename(aside / f"{path.name}.{int(time.time())}")
        say(f"{job.name}: its learner differs from this checkout's ({why}); made again")
        todo.append(job)
    say(f"{len(jobs)} runs, {len(jobs) - len(todo)} already made, {len(todo)} to do -> "
        f"{runs_dir}")
    if not todo:
        return 0
    return _execute(todo, module.run_job, lambda job, result: module.write_result(
        module.result_path(runs_dir, job), {**result, "machine": machine()}), parallel, address)


def _execute(todo: list[Any], work: Callable, keep: Callable, parallel: int,
             address: str | None) -> int:
    began, failed = time.monotonic(), []

    def done(index: int, job: Any, seconds: float) -> None:
        elapsed = time.monotonic() - began
        left = elapsed / index * (len(todo) - index)
        say(f"{index}/{len(todo)} {job.name} ({seconds:.0f} s); {elapsed / 60:.1f} min so far, "
            f"about {left / 60:.1f} min left")

    if address:
        from ray.util.multiprocessing import Pool

        with Pool(ray_address=address) as pool:
            for index, (job, result) in enumerate(
                    zip(todo, pool.imap(work, todo), strict=True), 1):
                keep(job, result)
                done(index, job, result.get("seconds", 0.0))
        return 0
    def finished(index: int, job: Any, outcome: Callable[[], dict]) -> None:
        try:
            result = outcome()
        except Exception as error:  # one failed run must not lose the others
            failed.append(job.name)
            say(f"{job.name} failed: {type(error).__name__}: {error}")
            return
        keep(job, result)
        done(index, job, result.get("seconds", 0.0))

    if parallel == 1:  # in this process: no pickling, a debugger works
        for index, job in enumerate(todo, 1):
            finished(index, job, lambda job=job: work(job))
    else:
        # Spawned, not forked: the calling process may hold threads (rclpy's, Ray's, a test
        # worker's), and a forked child that collects their objects can crash (seen under
        # load: a segmentation fault in the child's garbage collection).
        with ProcessPoolExecutor(parallel, mp_context=get_context("spawn")) as pool:
            futures = {pool.submit(work, job): job for job in todo}
            for index, future in enumerate(as_completed(futures), 1):
                finished(index, futures[future], future.result)
    if failed:
        say(f"failed: {', '.join(failed)}")
        return 1
    return 0
