"""Ctrl-C and SIGTERM stop a local sweep cleanly: the run under way is cancelled, the sweep
says so and exits 130, no graph outlives it, and no half-made run lands in the results (the
next sweep makes it). Before, Ray's own SIGTERM handler ended the driver on the spot, and a
sweep started in the background (SIGINT ignored) could not be stopped by SIGINT."""

from __future__ import annotations

import signal
import subprocess
import time

import pytest
import yaml

from sgim_nodes.sweep import results
from tests.conftest import REPO
from tests.sweep.processes import processes_left

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN_SWEEP = str(REPO / "ros_ws" / "run_sweep.sh")
# One run long enough to be interrupted while it moves.
SWEEP = {"movements": 3000, "eval_every": 1000, "seeds": 1, "learner": "random",
         "run_timeout": 900}


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_a_signal_stops_the_sweep_cleanly(tmp_path, sig):
    sweep = tmp_path / "one.yaml"
    sweep.write_text(yaml.safe_dump(SWEEP))
    runs = tmp_path / "runs"
    log = tmp_path / "driver.log"
    with log.open("wb") as out:
        driver = subprocess.Popen(
            [RUN_SWEEP, str(sweep), "--parallel", "1", "--runs-dir", str(runs), "--scratch",
             str(tmp_path / "scratch"), "--status-every", "1"],
            stdout=out, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + 300
        moving = False
        while not moving and time.monotonic() < deadline and driver.poll() is None:
            time.sleep(1)
            status = results.read_yaml(runs / results.STATUS_FILE) or {}
            moving = any(run.get("movements_done", 0) >= 10
                         for run in (status.get("runs") or {}).values())
        assert moving, "the run never started: " + log.read_text(errors="replace")[-3000:]
        driver.send_signal(sig)  # the driver alone, as a terminal's Ctrl-C or a kill would
        code = driver.wait(timeout=150)
    finally:
        if driver.poll() is None:
            driver.kill()
            driver.wait()
    text = log.read_text(errors="replace")
    assert code == 130, text[-3000:]
    assert "interrupted: stopping the runs under way" in text
    assert not processes_left(tmp_path, 60), "a graph of the sweep outlived it"
    status = results.read_yaml(runs / results.STATUS_FILE)
    assert status["counts"]["finished"] == 0
    assert not [p for p in runs.iterdir() if p.name != results.STATUS_FILE
                and not p.name.startswith(".")], "no half-made run in the results"
