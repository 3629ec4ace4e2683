"""Run a sweep file: every run through the node graph, each as a Ray task.

    ros_ws/run_sweep.sh sgim_nodes/config/sweeps/example.yaml             # Ray started here
    ros_ws/run_sweep.sh SWEEP.yaml --address HEAD:6379                     # join a cluster
    ros_ws/run_sweep.sh SWEEP.yaml --list                                  # the runs, no Ray

Without --address, Ray starts inside this command on this machine (--parallel runs side by
side) and stops with it. With --address it joins a running cluster, whose every machine has a
clone of this repository at the same commit, bootstrapped, and was started from a shell that
sourced ros_ws/env.sh (docs/guide.md). Runs are spread over the machines; each is made in a scratch
folder of its machine and copied back here (results.py, task.py). The sweep is resumable:
finished runs are skipped, and a run lost with its worker is retried by Ray (--max-retries)
and counted once. Progress is printed and kept in <runs-dir>/sweep_status.yaml.
"""

from __future__ import annotations

import argparse
import logging
import os
import secrets
import signal
import statistics
import sys
import time
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from sgim_nodes.graph.experiment_options import default_timeout
from sgim_nodes.sweep import results
from sgim_nodes.sweep.results import State
from sgim_nodes.sweep.sweep_file import RunSpec, Sweep, SweepFileError, load
from sgim_nodes.sweep.task import clean_stale, default_scratch, execute_run, worker_commit
from sgim_ros.command_line import BriefParser

HEAD_RESOURCE = "node:__internal_head__"


class Board:
    """Ray actor on the head node: which run runs where, its attempts and movements."""

    def __init__(self) -> None:
        self.runs: dict[str, dict[str, Any]] = {}

    def started(self, name: str, token: str, node_id: str, host: str, pid: int) -> None:
        attempts = self.runs.get(name, {}).get("attempts", 0) + 1
        self.runs[name] = {"token": token, "node_id": node_id, "host": host, "pid": pid,
                           "attempts": attempts, "movements": 0, "since": time.time()}

    def progress(self, name: str, token: str, movements: int) -> None:
        run = self.runs.get(name)
        if run is not None and run["token"] == token:  # not a late word of a lost attempt
            run["movements"] = movements

    def snapshot(self) -> dict[str, dict[str, Any]]:
        return self.runs


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    p = BriefParser(
        prog="ros_ws/run_sweep.sh",
        description="Expand a sweep file into runs and make each one through the node graph "
                    "as a Ray task, here or on a Ray cluster; resumable (finished runs are "
                    "skipped). The file's format: sgim_nodes/sgim_nodes/sweep/sweep_file.py "
                    "and docs/guide.md.")
    p.add_argument("sweep_file", type=Path, help="the sweep's YAML file")
    p.add_argument("--runs-dir", type=Path,
                   help="results directory, on this machine (default: the file's runs_dir, "
                        "else runs/<file name>)")
    p.add_argument("--address",
                   help="join this Ray cluster (HOST:PORT of its head, or 'auto' for the one "
                        "started on this machine) instead of starting Ray here")
    p.add_argument("--parallel", type=int, default=2,
                   help="without --address: runs side by side on this machine; one per core "
                        "is about right (default: %(default)s)")
    p.add_argument("--cpus-per-run", type=float, default=1.0,
                   help="Ray CPUs one run takes: a machine started with --num-cpus N makes "
                        "N / this runs at once (default: %(default)s)")
    p.add_argument("--object-store-memory", type=int, default=200 * 1024**2,
                   help="without --address: bytes of Ray's object store, which carries the "
                        "runs back (default: 200 MiB)")
    p.add_argument("--max-retries", type=int, default=3,
                   help="times a run lost with its worker or machine is started again "
                        "(default: %(default)s)")
    p.add_argument("--run-timeout", type=float,
                   help="abort a run after this many seconds (default: the file's "
                        "run_timeout, else run_experiment's: 600 + 0.5 per movement)")
    p.add_argument("--scratch",
                   help="folder where each machine makes its runs before sending them back "
                        f"(default: <its temp dir>/{default_scratch().name})")
    p.add_argument("--status-every", type=float, default=10.0,
                   help="seconds between progress lines (default: %(default)s)")
    p.add_argument("--list", action="store_true",
                   help="print every run, its state and its run_experiment command, and exit")
    p.add_argument("--keep-unlike", action="store_true",
                   help="keep finished runs whose learner fingerprint differs from this "
                        "checkout's (the learner changed since they were made) instead of "
                        "making them again; analyze will then refuse to pool them")
    args = p.parse_args(argv)
    if args.parallel < 1 or args.cpus_per_run <= 0 or args.max_retries < 0:
        p.error("--parallel must be >= 1, --cpus-per-run > 0 and --max-retries >= 0")
    return args


def say(message: str) -> None:
    print(f"[sweep] {message}", file=sys.stderr, flush=True)


def _interrupt(*_: object) -> None:
    raise KeyboardInterrupt


class Progress:
    """What the driver knows of every run, printed and written to sweep_status.yaml."""

    def __init__(self, sweep: Sweep, states: dict[str, results.RunState], ray_where: str
                 ) -> None:
        self.sweep, self.ray_where = sweep, ray_where
        self.began = time.monotonic()
        self.started = datetime.now(UTC).isoformat()
        self.state = {spec.name: ("skipped" if states[spec.name].state is State.FINISHED
                                  else "pending") for spec in sweep.runs}
        self.detail: dict[str, str] = {}
        self.board: dict[str, dict[str, Any]] = {}
        self.nodes: dict[str, dict[str, Any]] = {}
        self.overheads: list[float] = []

    def label(self, node_id: str) -> str:
        node = self.nodes.get(node_id)
        if node is None:
            return node_id[:8]
        return "head" if node["head"] else f"{node['address']}/{node_id[:6]}"

    def counts(self) -> dict[str, int]:
        running = [n for n, s in self.state.items() if s == "pending" and n in self.board]
        out = {"runs": len(self.state), "skipped": 0, "finished": 0, "failed": 0}
        for s in self.state.values():
            if s in out:
                out[s] += 1
        out["running"] = len(running)
        out["pending"] = sum(1 for s in self.state.values() if s == "pending") - len(running)
        out["retried"] = sum(1 for r in self.board.values() if r["attempts"] > 1)
        return out

    def line(self) -> str:
        c = self.counts()
        done = c["finished"] + c["skipped"]
        running = [f"{name} {r['movements']}/{self._spec(name).movements} "
                   f"@{self.label(r['node_id'])}" + (f" (attempt {r['attempts']})"
                                                      if r["attempts"] > 1 else "")
                   for name, r in self.board.items() if self.state[name] == "pending"]
        minutes = (time.monotonic() - self.began) / 60
        return (f"{done}/{c['runs']} runs done ({c['skipped']} before), {c['running']} "
                f"running, {c['pending']} waiting, {c['failed']} failed, {c['retried']} "
                f"retried, {minutes:.1f} min" + (" | " + " | ".join(running) if running else ""))

    def _spec(self, name: str) -> RunSpec:
        return next(s for s in self.sweep.runs if s.name == name)

    def write(self) -> None:
        runs = {}
        for spec in self.sweep.runs:
            entry: dict[str, Any] = {"state": self.state[spec.name], **spec.settings()}
            board = self.board.get(spec.name)
            if board is not None:
                entry.update(node=self.label(board["node_id"]), node_id=board["node_id"],
                             attempts=board["attempts"], movements_done=board["movements"])
            if spec.name in self.detail:
                entry["detail"] = self.detail[spec.name]
            runs[spec.name] = entry
        results.write_yaml(self.sweep.runs_dir / results.STATUS_FILE, {
            "sweep": str(self.sweep.path), "ray": self.ray_where, "started": self.started,
            "updated": datetime.now(UTC).isoformat(), "counts": self.counts(),
            "nodes": self.nodes, "runs": runs})


def _nodes(ray: Any) -> dict[str, dict[str, Any]]:
    return {n["NodeID"]: {"address": n["NodeManagerAddress"], "alive": bool(n["Alive"]),
                          "head": HEAD_RESOURCE in n.get("Resources", {}),
                          "cpus": n.get("Resources", {}).get("CPU", 0)}
            for n in ray.nodes()}


def _start_ray(args: argparse.Namespace) -> tuple[Any, str]:
    if not args.address and "RAY_AUTH_MODE" not in os.environ:
        # The Ray started here takes a token of its own, in its processes' environment only
        # (read when ray is imported): nothing is read from or written to ~/.ray.
        os.environ.update(RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=secrets.token_hex(32))
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # nothing sent anywhere
    import ray

    common = {"log_to_driver": False, "logging_level": logging.WARNING}
    if args.address:
        ray.init(address=args.address, **common)
        return ray, args.address
    ray.init(address="local", num_cpus=args.parallel, include_dashboard=False,
             object_store_memory=args.object_store_memory, **common)
    return ray, f"local ({args.parallel} side by side)"


def stop_on_signals() -> None:
    """Ctrl-C and SIGTERM stop the sweep cleanly (the runs under way cancelled, the status
    written). Set after ray.init: Ray replaces SIGTERM's handler with one that ends the
    process on the spot, and its driver let Ctrl-C pass without stopping the sweep."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _interrupt)


def _collect(ray: Any, ref: Any, spec: RunSpec, sweep: Sweep, progress: Progress,
             commit: str, warned: set[str]) -> None:
    """One finished task: its run installed in the results directory, its state recorded."""
    try:
        result = ray.get(ref)
    except ray.exceptions.RayError as error:
        progress.state[spec.name] = "failed"
        first = str(error).strip().splitlines()
        progress.detail[spec.name] = f"{type(error).__name__}: {first[-1] if first else ''}"
        say(f"{spec.name} failed: {progress.detail[spec.name]}")
        return
    board = progress.board.get(spec.name, {})
    if result["commit"] != commit and result["node_id"] not in warned:
        warned.add(result["node_id"])
        say(f"warning: node {progress.label(result['node_id'])} runs commit "
            f"{result['commit']}, this driver {commit}")
    installing = time.time()
    record = {"sweep": str(sweep.path), "settings": spec.settings(),
              "node": {"id": result["node_id"], "label": progress.label(result["node_id"]),
                       "hostname": result["hostname"], "worker_pid": result["pid"],
                       **({"machine": result["machine"]} if "machine" in result else {})},
              "attempts": board.get("attempts", 1), "worker_commit": result["commit"],
              "task_started": datetime.fromtimestamp(result["started"], UTC).isoformat(),
              "task_ended": datetime.fromtimestamp(result["ended"], UTC).isoformat(),
              "launch_s": result["launch_s"], "run_s": result["run_s"],
              "pack_s": result["pack_s"], "archive_bytes": len(result["archive"])}
    try:
        folder = results.install(sweep.runs_dir, spec, result["archive"], record)
    except (OSError, ValueError) as error:
        progress.state[spec.name] = "failed"
        progress.detail[spec.name] = f"could not install the run: {error}"
        say(f"{spec.name}: {progress.detail[spec.name]}")
        return
    installed = time.time() - installing
    state = results.run_state(folder, spec)
    if state.state is State.FINISHED:
        progress.state[spec.name] = "finished"
        progress.overheads.append(result["launch_s"] + result["pack_s"] + installed)
    else:
        progress.state[spec.name] = "failed"
        progress.detail[spec.name] = f"{result['outcome']} ({state.reason or state.state.value})"
        say(f"{spec.name} did not finish: {progress.detail[spec.name]}; see {folder}/logs")


def _refresh(ray: Any, board: Any, progress: Progress) -> None:
    try:
        progress.board = ray.get(board.snapshot.remote(), timeout=30)
        progress.nodes = _nodes(ray)
    except Exception as error:  # a slow answer only delays the next line
        say(f"progress unavailable this time ({type(error).__name__})")


def run_sweep(sweep: Sweep, args: argparse.Namespace, todo: list[RunSpec],
              states: dict[str, results.RunState]) -> int:
    try:
        ray, where = _start_ray(args)
    except Exception as error:  # Ray start-up errors are of many kinds
        say(f"could not start or join Ray: {error}")
        return 1
    stop_on_signals()
    progress = Progress(sweep, states, where)
    # On the head: the one node whose loss ends the cluster anyway.
    board = ray.remote(Board).options(num_cpus=0, resources={HEAD_RESOURCE: 0.001}).remote()
    remote_run = ray.remote(execute_run).options(
        num_cpus=args.cpus_per_run, max_retries=args.max_retries, scheduling_strategy="SPREAD")
    pending = {remote_run.remote(spec, args.run_timeout or sweep.run_timeout
                                 or default_timeout(spec.movements), args.scratch, board): spec
               for spec in todo}
    progress.nodes = _nodes(ray)
    cpus = sum(n["cpus"] for n in progress.nodes.values() if n["alive"])
    say(f"Ray: {where}, {len(progress.nodes)} node(s), {cpus:g} CPUs; {len(todo)} runs "
        f"submitted")
    commit, warned = worker_commit(), set()
    last = 0.0
    code = 0
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1, timeout=1.0)
            if ready or time.monotonic() - last > args.status_every:
                _refresh(ray, board, progress)
            for ref in ready:
                _collect(ray, ref, pending.pop(ref), sweep, progress, commit, warned)
            if ready or time.monotonic() - last > args.status_every:
                progress.write()
            if time.monotonic() - last > args.status_every:
                last = time.monotonic()
                say(progress.line())
    except KeyboardInterrupt:
        say("interrupted: stopping the runs under way (run the sweep again to resume)")
        for ref in pending:
            ray.cancel(ref)
        ray.wait(list(pending), num_returns=len(pending), timeout=90)
        code = 130
    _refresh(ray, board, progress)
    progress.write()
    _summary(progress)
    ray.shutdown()
    # This machine's part of the scratch; other machines clean theirs at their next task.
    clean_stale(Path(args.scratch) if args.scratch else default_scratch())
    if code:
        return code
    return 1 if progress.counts()["failed"] else 0


def _summary(progress: Progress) -> None:
    c = progress.counts()
    say(progress.line())
    per_node: dict[str, int] = {}
    for name, state in progress.state.items():
        if state == "finished" and name in progress.board:
            label = progress.label(progress.board[name]["node_id"])
            per_node[label] = per_node.get(label, 0) + 1
    if per_node:
        say("runs made per node: " + ", ".join(f"{k} {v}" for k, v in sorted(per_node.items())))
    if progress.overheads:
        say(f"Ray's cost per run (start in the task, pack, install): median "
            f"{statistics.median(progress.overheads):.2f} s")
    failed = [n for n, s in progress.state.items() if s == "failed"]
    minutes = (time.monotonic() - progress.began) / 60
    say(f"{c['finished'] + c['skipped']}/{c['runs']} runs finished in {minutes:.1f} min"
        + (f"; failed: {', '.join(failed)}" if failed else "")
        + f" -> {progress.sweep.runs_dir}")


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        sweep = load(args.sweep_file, args.runs_dir)
    except SweepFileError as error:
        print(f"run_sweep: {error}", file=sys.stderr)
        return 2
    return drive(sweep, args)


def drive(sweep: Sweep, args: argparse.Namespace) -> int:
    """Make the sweep's runs that are not finished (or list them, with --list)."""
    states = {spec.name: results.run_state(sweep.runs_dir / spec.name, spec)
              for spec in sweep.runs}
    if args.list:
        for spec in sweep.runs:
            state = states[spec.name]
            print(f"{spec.name}\t{state.state.value}\t{' '.join(spec.argv())}"
                  + (f"\t# {state.reason}" if state.reason else ""))
        return 0
    mismatched = {n: s.reason for n, s in states.items() if s.state is State.MISMATCH}
    if mismatched:
        for name, reason in mismatched.items():
            print(f"run_sweep: {sweep.runs_dir / name} is a finished run of other settings "
                  f"({reason})", file=sys.stderr)
        print("run_sweep: choose another --runs-dir, or move those runs away", file=sys.stderr)
        return 2
    try:
        lock = results.lock_results(sweep.runs_dir)
    except results.ResultsBusy as error:
        print(f"run_sweep: {error}", file=sys.stderr)
        return 2
    unlike = {n: s.reason for n, s in states.items() if s.state is State.UNLIKE}
    with lock:
        results.clean_incoming(sweep.runs_dir)
        for name, reason in unlike.items():
            if args.keep_unlike:
                say(f"{name}: {reason}; kept (--keep-unlike)")
                states[name] = results.RunState(State.FINISHED, reason)
            else:
                aside = results.set_aside(sweep.runs_dir, name)
                say(f"{name}: {reason}; made again (the old run moved to {aside})")
                states[name] = results.RunState(State.ABSENT)
        todo = [s for s in sweep.runs if states[s.name].state is not State.FINISHED]
        say(f"{sweep.name}: {len(sweep.runs)} runs, {len(sweep.runs) - len(todo)} already "
            f"finished, {len(todo)} to do -> {sweep.runs_dir}")
        if not todo:
            return 0
        previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
        signal.signal(signal.SIGTERM, _interrupt)
        try:
            return run_sweep(sweep, args, todo, states)
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)
            results.clean_incoming(sweep.runs_dir)


if __name__ == "__main__":
    raise SystemExit(main())
