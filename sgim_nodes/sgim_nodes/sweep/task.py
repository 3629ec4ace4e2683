"""One run of a sweep on a Ray worker: run_experiment in a scratch folder, a tarball back.

The worker runs the graph with its own copy of the repository (the one this module was
imported from: every machine of the cluster has a clone, bootstrapped, at the same commit),
through ``ros_ws/run_experiment.sh``, which reserves a ROS domain no other run on the machine
holds (a loopback port lock), so two workers of one machine never share one.

The run is made in ``<scratch>/<run>.<token>/`` on the worker's machine and sent back whole, as
a gzip'ed tar, in the task's result: the driver alone writes the results directory
(results.py). A scratch folder is owned through a lock file that the worker and its
run_experiment hold (flock, freed by the kernel when both are gone): a folder whose lock is
free belongs to a dead task and is removed by the next task on that machine.

run_experiment is started as run_study starts it, through a ProcessGroup (graph/processes.py):
it gets a lifeline from this worker and stops its graph, as on Ctrl-C, when the worker ends
however it ends (its machine's raylet lost, the task cancelled, killed); its nodes follow
their launcher the same way, so no node outlives its run.
"""

from __future__ import annotations

import contextlib
import fcntl
import io
import os
import shutil
import signal
import socket
import subprocess
import tarfile
import tempfile
import time
import uuid
from functools import cache
from pathlib import Path
from typing import Any

from sgim_nodes.graph.batch import PROGRESS
from sgim_nodes.graph.experiment_options import REPO
from sgim_nodes.graph.processes import ProcessGroup, node_log
from sgim_nodes.provenance.record import machine
from sgim_nodes.sweep.results import read_yaml
from sgim_nodes.sweep.sweep_file import RunSpec

RUN_EXPERIMENT = REPO / "ros_ws" / "run_experiment.sh"
SCRATCH_NAME = "sgim-sweep"
POLL_S = 2.0
STOP_GRACE_S = 60.0  # run_experiment stops every node, the recorder closes its bag
HARD_LIMIT_MARGIN_S = 300.0  # beyond run_experiment's own --timeout
LAUNCHER_LOG = "run_experiment.out"  # its output (its own launcher.log is in logs/ too)


def default_scratch() -> Path:
    return Path(tempfile.gettempdir()) / SCRATCH_NAME


def _lock(path: Path) -> io.TextIOWrapper:
    """Create `path` already locked: made under another name, locked, then renamed, so that
    clean_stale never sees it unlocked."""
    making = path.with_name(f".{path.name}.{os.getpid()}")
    handle = making.open("a+")
    fcntl.flock(handle, fcntl.LOCK_EX)
    making.rename(path)
    return handle


def clean_stale(scratch: Path) -> list[str]:
    """Remove the scratch folders of dead tasks on this machine; their names."""
    removed = []
    for lock in sorted(scratch.glob("*.lock")):
        try:
            handle = lock.open("a+")
        except OSError:
            continue
        with handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                continue  # a live task (or its run_experiment) holds it
            shutil.rmtree(lock.with_suffix(""), ignore_errors=True)
            lock.unlink(missing_ok=True)
            removed.append(lock.stem)
    return removed


def movements_done(run_dir: Path, window: int = 4096, most: int = 1 << 20) -> int:
    """The arbiter's last progress line ("N/M movements") in its log. The tail read grows
    until it holds one: SGIM-ACTS's arbiter writes a line per request between them."""
    try:
        with node_log(run_dir / "logs", "social_interaction").open("rb") as f:
            size = f.seek(0, os.SEEK_END)
            while True:
                f.seek(max(0, size - window))
                found = PROGRESS.findall(f.read().decode(errors="replace"))
                if found or window >= min(size, most):
                    return int(found[-1][0]) if found else 0
                window *= 4
    except OSError:
        return 0


@cache
def worker_commit() -> str:
    try:
        return subprocess.run(["git", "-C", str(REPO), "describe", "--always", "--dirty"],
                              capture_output=True, text=True, timeout=30).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def _stop(launcher: subprocess.Popen, group: ProcessGroup) -> None:
    """One SIGTERM to run_experiment (it stops its graph, as on Ctrl-C, and writes its
    metadata); after a grace period the group's SIGINT, SIGTERM, SIGKILL, a last resort."""
    if launcher.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            launcher.send_signal(signal.SIGTERM)
        with contextlib.suppress(subprocess.TimeoutExpired):
            launcher.wait(timeout=STOP_GRACE_S)
    group.stop_all()
    group.close()


def _notify(board: Any, method: str, *args: Any) -> None:
    """Tell the progress board, never failing the run for it."""
    if board is not None:
        with contextlib.suppress(Exception):
            getattr(board, method).remote(*args)


def _pack(run_dir: Path, name: str) -> bytes:
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz", compresslevel=1) as tar:
        tar.add(run_dir, arcname=name)
    return buffer.getvalue()


def execute_run(spec: RunSpec, timeout: float, scratch: str | None = None,
                board: Any = None) -> dict[str, Any]:
    """Make one run on this machine; its folder comes back as a tarball in the result."""
    import ray

    began = time.time()
    node_id = ray.get_runtime_context().get_node_id()
    base = Path(scratch) if scratch else default_scratch()
    base.mkdir(parents=True, exist_ok=True)
    clean_stale(base)
    token = uuid.uuid4().hex[:10]
    lock = _lock(base / f"{spec.name}.{token}.lock")
    work = base / f"{spec.name}.{token}"
    work.mkdir()
    run_dir = work / spec.name
    host = socket.gethostname()
    _notify(board, "started", spec.name, token, node_id, host, os.getpid())
    try:
        # --no-markers: a worker's run is in a domain of its own that no viewer joins, and
        # the markers node cost 4 % of the graph's CPU for nobody (docs/notes/measurements.md)
        argv = [str(RUN_EXPERIMENT), *spec.argv(), "--runs-dir", str(work), "--name",
                spec.name, "--quiet", "--no-markers", "--timeout", f"{timeout:g}"]
        # run_experiment holds the scratch folder's lock too, until it is gone
        group = ProcessGroup(inherited_fds=(lock.fileno(),))
        with (work / LAUNCHER_LOG).open("wb") as log:
            proc = group.start("run_experiment", argv, stdin=subprocess.DEVNULL, stdout=log,
                               stderr=subprocess.STDOUT, cwd=REPO)
        launched = time.time()
        try:
            shown = -1
            while proc.poll() is None:
                with contextlib.suppress(subprocess.TimeoutExpired):
                    proc.wait(timeout=POLL_S)
                done = movements_done(run_dir)
                if done != shown:
                    _notify(board, "progress", spec.name, token, done)
                    shown = done
                if time.time() - launched > timeout + HARD_LIMIT_MARGIN_S:
                    break
        finally:  # cancelled (KeyboardInterrupt), failing or too long: the graph stops here
            _stop(proc, group)
        ran = time.time() - launched
        (run_dir / "logs").mkdir(parents=True, exist_ok=True)
        shutil.move(work / LAUNCHER_LOG, run_dir / "logs" / LAUNCHER_LOG)
        meta = read_yaml(run_dir / "metadata.yaml")
        meta = meta if isinstance(meta, dict) else {}
        packing = time.time()
        archive = _pack(run_dir, spec.name)
        return {"name": spec.name, "returncode": proc.returncode,
                "outcome": meta.get("outcome", "no metadata.yaml"),
                "node_id": node_id, "hostname": host, "machine": machine(), "pid": os.getpid(),
                "token": token,
                "commit": worker_commit(), "started": began, "ended": time.time(),
                "launch_s": round(launched - began, 3), "run_s": round(ran, 3),
                "pack_s": round(time.time() - packing, 3), "archive": archive}
    finally:
        shutil.rmtree(work, ignore_errors=True)
        lock.close()
        (base / f"{spec.name}.{token}.lock").unlink(missing_ok=True)
