"""Run the paper's study: learners x seeds through the node graph, several runs side by side.

Each run is one `run_experiment` (its own ROS domain, its own bag) in <runs-dir>/<learner>-
seed<N>. Finished runs are skipped, so an interrupted study resumes where it stopped; a run
that did not finish is started again from scratch. Progress is shown per run and overall.

    ros_ws/run_study.sh                       # 5 learners x 10 seeds x 5000 movements
    ros_ws/run_study.sh --seeds 3 --movements 1000 --parallel 2
    ros_ws/run_study.sh --learners sgim-d --param timing=on-request --runs-dir runs/asks

Every --param is checked for every learner before any run starts (a social mode a learner
cannot play, e.g. demo-only with timing on-request, is refused). Run folders are named by
learner and seed only: give each setting its own --runs-dir (or use a sweep file, whose run
names carry their settings).
"""

from __future__ import annotations

import argparse
import math
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from sgim_nodes.core.learner_registry import compared_names
from sgim_nodes.graph.description import ARBITER, RunOptions, parameters
from sgim_nodes.graph.overrides import parse_assignments
from sgim_nodes.graph.processes import ProcessGroup, node_log
from sgim_nodes.graph.run_folder import RunFolderError, RunLock
from sgim_ros.command_line import BriefParser
from sgim_ros.params import SEED_MAX, ParameterError

REPO = Path(__file__).resolve().parents[3]
RUN = REPO / "ros_ws" / "run_experiment.sh"
PROGRESS = re.compile(r"(\d+)/(\d+) movements")


@dataclass
class Job:
    learner: str
    seed: int
    folder: Path
    process: subprocess.Popen | None = None
    started: float = 0.0
    log: object = field(default=None, repr=False)

    @property
    def name(self) -> str:
        return self.folder.name

    def movements_done(self) -> int:
        log = node_log(self.folder / "logs", ARBITER)
        try:
            tail = log.read_text(errors="replace")[-2000:]
        except OSError:
            return 0
        found = PROGRESS.findall(tail)
        return int(found[-1][0]) if found else 0


def finished(folder: Path) -> bool:
    try:
        meta = yaml.safe_load((folder / "metadata.yaml").read_text())
    except (OSError, yaml.YAMLError):
        return False
    return isinstance(meta, dict) and meta.get("outcome") == "finished"


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    p = BriefParser(
        prog="ros_ws/run_study.sh",
        description="Run learners x seeds through the node graph (the paper's comparison), "
                    "resumable: finished runs are skipped.")
    p.add_argument("--learners", nargs="+", choices=compared_names(),
                   default=list(compared_names()),
                   help="learners to run (default: all five)")
    p.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 (default: 10)")
    p.add_argument("--first-seed", type=int, default=0, help="first seed (default: 0)")
    p.add_argument("--movements", type=int, default=5000,
                   help="movements per run; the paper's 5000 (default: %(default)s)")
    p.add_argument("--eval-every", type=int, default=250,
                   help="movements between evaluations (default: %(default)s)")
    p.add_argument("--parallel", type=int, default=2,
                   help="runs side by side; one per core is about right (default: 2)")
    p.add_argument("--runs-dir", type=Path, default=REPO / "runs" / "study",
                   help="folder of the study's runs (default: runs/study)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="passed to every run (see run_experiment.sh --help), e.g. "
                        "timing=on-request or demonstration_content=goal-only; checked for "
                        "every learner first. Folders are named by learner and seed only: "
                        "give each setting its own --runs-dir")
    p.add_argument("--run-timeout", type=float, default=3600,
                   help="abort a run after this many seconds (default: 3600)")
    args = p.parse_args(argv)
    if args.seeds < 1 or args.parallel < 1 or args.movements < 1:
        p.error("--seeds, --parallel and --movements must be >= 1")
    if args.first_seed < 0 or args.seeds - 1 > SEED_MAX:
        p.error(f"the seeds must lie in 0..{SEED_MAX} (2**32 - 1), the graph's range")
    if not (args.run_timeout > 0 and math.isfinite(args.run_timeout)):
        p.error("--run-timeout must be a number of seconds > 0")
    try:
        check_params(args.learners, args.param, args.movements, args.eval_every)
    except ParameterError as error:
        p.error(str(error))
    return args


def check_params(learners: Sequence[str], items: Sequence[str], movements: int,
                 eval_every: int) -> None:
    """Every --param as run_experiment will check it, for each learner: ParameterError naming
    the learner that cannot take it."""
    assigned, where = parse_assignments(items)
    for learner in learners:
        try:
            parameters(RunOptions(learner, movements=movements, eval_every=eval_every,
                                  overrides=assigned), where=where)
        except ParameterError as error:
            raise ParameterError(f"{learner}: {error}") from None


def start(job: Job, args: argparse.Namespace, group: ProcessGroup) -> bool:
    """Start the run's launcher; False if its folder is in use by a launcher still alive."""
    if job.folder.exists():  # an unfinished run: start it again from scratch
        try:
            RunLock.take(job.folder).release()
        except RunFolderError as error:
            print(f"[study] {job.name} skipped: {error}", file=sys.stderr)
            return False
        shutil.rmtree(job.folder)
    argv = [str(RUN), job.learner, "--seed", str(job.seed), "--movements", str(args.movements),
            "--eval-every", str(args.eval_every), "--runs-dir", str(args.runs_dir), "--name",
            job.name, "--quiet", "--no-markers", "--timeout", str(args.run_timeout)]
    for item in args.param:
        argv += ["--param", item]
    args.runs_dir.mkdir(parents=True, exist_ok=True)
    job.log = open(args.runs_dir / f"{job.name}.launcher.log", "w")  # noqa: SIM115
    # The group's lifeline: if this study dies, however, its launchers stop their runs.
    job.process = group.start(job.name, argv, stdout=job.log, stderr=subprocess.STDOUT)
    job.started = time.monotonic()
    return True


def report(jobs: list[Job], done: int, failed: list[str], total: int, movements: int,
           began: float) -> None:
    running = [j for j in jobs if j.process is not None and j.process.poll() is None]
    parts = [f"{j.name} {100 * j.movements_done() // movements:3d}%" for j in running]
    elapsed = time.monotonic() - began
    line = (f"[study] {done}/{total} runs done, {len(failed)} failed, "
            f"{elapsed / 60:.1f} min | " + " | ".join(parts))
    print(line, file=sys.stderr, flush=True)


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    jobs = [Job(learner, seed, args.runs_dir / f"{learner}-seed{seed}")
            for seed in range(args.first_seed, args.first_seed + args.seeds)
            for learner in args.learners]
    todo = [j for j in jobs if not finished(j.folder)]
    print(f"[study] {len(jobs)} runs, {len(jobs) - len(todo)} already finished, "
          f"{len(todo)} to do, {args.parallel} side by side -> {args.runs_dir}", file=sys.stderr)
    began, last_report = time.monotonic(), 0.0
    running: list[Job] = []
    failed: list[str] = []
    done = len(jobs) - len(todo)
    group = ProcessGroup()
    try:
        while todo or running:
            while todo and len(running) < args.parallel:
                job = todo.pop(0)
                if start(job, args, group):
                    running.append(job)
                else:
                    failed.append(job.name)
            for job in list(running):
                if job.process.poll() is None:
                    continue
                running.remove(job)
                job.log.close()
                if finished(job.folder):
                    done += 1
                else:
                    failed.append(job.name)
                    print(f"[study] {job.name} did not finish (exit {job.process.returncode}); "
                          f"see {job.folder}", file=sys.stderr)
            if time.monotonic() - last_report > 10:
                last_report = time.monotonic()
                report(running, done, failed, len(jobs), args.movements, began)
            time.sleep(0.5)
    except KeyboardInterrupt:
        print("[study] interrupted: stopping the runs under way (run again to resume)",
              file=sys.stderr)
        for job in running:
            job.process.send_signal(signal.SIGINT)
        for job in running:
            try:
                job.process.wait(timeout=60)
            except subprocess.TimeoutExpired:
                job.process.kill()
        return 130
    finally:
        group.close()
    minutes = (time.monotonic() - began) / 60
    print(f"[study] {done}/{len(jobs)} runs finished in {minutes:.1f} min"
          + (f"; failed: {', '.join(failed)}" if failed else ""), file=sys.stderr)
    return 0 if not failed else 1


if __name__ == "__main__":
    raise SystemExit(main())
