"""A sweep on a Ray cluster of two nodes on this machine (a head and a worker, `ray start`):
both nodes make runs, every run lands once and complete, and losing the worker mid-sweep still
ends with every run made exactly once."""

from __future__ import annotations

import itertools
import shutil
import subprocess
import tempfile
import time
from collections.abc import Iterator
from datetime import datetime
from pathlib import Path

import pytest
import yaml

from sgim_nodes.bag.run_folder import load_run_folder, segments
from sgim_nodes.sweep import results, task
from sgim_nodes.sweep.results import State
from sgim_nodes.sweep.sweep_file import RunSpec, load
from tests.conftest import REPO
from tests.sweep.processes import processes_left
from tests.sweep.ray_cluster import LocalCluster

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN_SWEEP = str(REPO / "ros_ws" / "run_sweep.sh")
# 2 seeds x 100 movements: a run for each node, and one to lose with the worker. (A list of
# settings multiplies the runs, which tests/sweep/test_sweep_file.py checks without Ray.)
SWEEP = {"movements": 100, "eval_every": 50, "seeds": 2, "learner": "sgim-d",
         "demonstration_period": 50, "run_timeout": 600}
RUNS = 2
SWEEP_TIMEOUT = 1500  # seconds; a 100-movement run takes about 35 s on 2 loaded cores


@pytest.fixture(scope="module")
def cluster() -> Iterator[LocalCluster]:
    # Ray's socket paths must stay under 108 characters: a short folder of its own
    root = Path(tempfile.mkdtemp(prefix="sgray-", dir="/tmp"))
    nodes = LocalCluster(root)
    try:
        nodes.start(workers=1)
        yield nodes
    finally:
        nodes.stop()
        left = [pid for node in nodes.nodes for pid in node.members()]
        shutil.rmtree(root, ignore_errors=True)
        assert not left, f"Ray processes left behind: {left}"


def sweep_file(tmp_path: Path) -> Path:
    path = tmp_path / "two_by_two.yaml"
    path.write_text(yaml.safe_dump(SWEEP))
    return path


def start_sweep(cluster: LocalCluster, tmp_path: Path) -> tuple[subprocess.Popen, Path]:
    log = tmp_path / "driver.log"
    with log.open("wb") as out:
        driver = subprocess.Popen(
            [RUN_SWEEP, str(sweep_file(tmp_path)), "--address", cluster.address, "--runs-dir",
             str(tmp_path / "runs"), "--scratch", str(tmp_path / "scratch"), "--status-every",
             "2"], stdout=out, stderr=subprocess.STDOUT, start_new_session=True, env=cluster.env)
    return driver, log


def finish(driver: subprocess.Popen, log: Path) -> str:
    try:
        driver.wait(timeout=SWEEP_TIMEOUT)
    except subprocess.TimeoutExpired:
        driver.terminate()
        driver.wait(timeout=120)
    text = log.read_text(errors="replace")
    assert driver.returncode == 0, text[-4000:]
    return text


def made_once(runs: Path, spec: RunSpec) -> dict:
    """The run is finished and complete, made in one go: every movement index exactly once."""
    folder = runs / spec.name
    state = results.run_state(folder, spec)
    assert state.state is State.FINISHED, f"{spec.name}: {state}"
    assert [p.name for p in segments(folder)] == ["bag"], "made once, never resumed"
    records = load_run_folder(folder)
    assert [m.index for m in records.movements] == list(range(1, spec.movements + 1))
    assert not records.quarantined
    return yaml.safe_load((folder / results.RUN_RECORD).read_text())


def check_results(tmp_path: Path) -> dict[str, dict]:
    runs = tmp_path / "runs"
    specs = load(sweep_file(tmp_path), runs).runs
    assert len(specs) == RUNS
    made = {spec.name: made_once(runs, spec) for spec in specs}
    listed = sorted(p.name for p in runs.iterdir() if not p.name.startswith("."))
    assert listed == sorted([*made, results.STATUS_FILE]), "one folder per run, nothing else"
    assert not (runs / results.INCOMING).exists()
    return made


def domains_never_shared(runs: Path, names: list[str]) -> int:
    """Runs that overlapped in time had different ROS domains; how many pairs overlapped."""
    spans = {}
    for name in names:
        meta = yaml.safe_load((runs / name / "metadata.yaml").read_text())
        spans[name] = (datetime.fromisoformat(meta["started"]),
                       datetime.fromisoformat(meta["ended"]), meta["ros_domain_id"])
    overlapping = 0
    for a, b in itertools.combinations(names, 2):
        (s1, e1, d1), (s2, e2, d2) = spans[a], spans[b]
        if s1 < e2 and s2 < e1:
            overlapping += 1
            assert d1 != d2, f"{a} and {b} ran at once on domain {d1}"
    return overlapping


def nothing_left(tmp_path: Path, lost: bool = False, timeout: float = 120) -> None:
    """No graph outlives the sweep, and its scratch folders are gone; a task lost with its
    machine leaves its folder to the next task there (clean_stale), which finds it free."""
    assert not processes_left(tmp_path, timeout), "a graph of the sweep outlived it"
    scratch = tmp_path / "scratch"
    if lost:
        task.clean_stale(scratch)
    assert not list(scratch.iterdir()), "scratch folders left behind"


def test_a_sweep_on_two_nodes_uses_both_and_lands_every_run_once(cluster, tmp_path):
    driver, log = start_sweep(cluster, tmp_path)
    output = finish(driver, log)
    made = check_results(tmp_path)
    nodes = {record["node"]["id"]: record["node"]["label"] for record in made.values()}
    assert len(nodes) == 2 and "head" in nodes.values(), f"runs per node: {made}"
    workers = {(r["node"]["id"], r["node"]["worker_pid"]) for r in made.values()}
    assert len({pid for _, pid in workers}) >= 2, "two nodes, two worker processes at least"
    assert all(record["attempts"] == 1 for record in made.values())
    assert domains_never_shared(tmp_path / "runs", list(made)) >= 1, "no two runs at once"
    assert f"{RUNS}/{RUNS} runs finished" in output
    nothing_left(tmp_path)


def test_losing_the_worker_mid_sweep_still_makes_every_run_once(cluster, tmp_path):
    worker = next(node for node in cluster.nodes if node.name != "head")
    driver, log = start_sweep(cluster, tmp_path)
    status_file = tmp_path / "runs" / results.STATUS_FILE
    victim = None
    deadline = time.monotonic() + 900
    while victim is None and time.monotonic() < deadline and driver.poll() is None:
        time.sleep(1)
        status = results.read_yaml(status_file) or {}
        for name, run in (status.get("runs") or {}).items():
            if (run.get("state") == "pending" and run.get("node") not in (None, "head")
                    and run.get("movements_done", 0) >= 10):
                victim = name
    assert victim is not None, "the worker never ran a run: " + log.read_text()[-3000:]
    worker.kill()
    finish(driver, log)
    made = check_results(tmp_path)
    assert made[victim]["attempts"] >= 2, made[victim]
    assert made[victim]["node"]["label"] == "head"
    counts = results.read_yaml(status_file)["counts"]
    assert counts["finished"] == RUNS and counts["failed"] == 0 and counts["retried"] >= 1
    nothing_left(tmp_path, lost=True)
