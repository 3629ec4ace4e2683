"""bench_graph_vs_runner.py --profile: each node's CPU split into rclpy's executor, the
physics and the rest, read from the profiles the nodes write (sgim_ros/entry.py)."""

from __future__ import annotations

import importlib.util
import sys
import time

from sgim_ros.entry import PROFILE_ENV, Profile
from tests.benchmarks.scripts import load_benchmark


def load_bench():
    return load_benchmark("bench_graph_vs_runner")


def busy(seconds: float) -> None:
    end = time.thread_time() + seconds
    while time.thread_time() < end:
        pass


def test_the_executors_share_is_told_apart_from_the_nodes_own_work(tmp_path, monkeypatch):
    # A stand-in for rclpy's executor: a function of that name in a file rclpy/executors.py.
    fake = tmp_path / "fake" / "rclpy"
    fake.mkdir(parents=True)
    (fake / "executors.py").write_text(
        "import time\n"
        "def _wait_for_ready_callbacks(seconds):\n"
        "    end = time.thread_time() + seconds\n"
        "    while time.thread_time() < end:\n"
        "        pass\n")
    spec = importlib.util.spec_from_file_location("fake_executors", fake / "executors.py")
    executors = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(executors)
    monkeypatch.setitem(sys.modules, "fake_executors", executors)
    monkeypatch.setenv(PROFILE_ENV, str(tmp_path / "profile"))
    with Profile("arbiter") as profile:
        executors._wait_for_ready_callbacks(0.3)
        busy(0.1)
    profile.write()

    (line,) = load_bench().profile_shares(tmp_path / "profile")
    name, rest = line.split(maxsplit=1)
    assert name == "arbiter"
    executor = int(rest.split("rclpy executor")[1].split("%")[0])
    other = int(rest.split("the rest")[1].split("%")[0])
    assert 60 <= executor <= 90 and 10 <= other <= 40, line
    assert "physics   0 %" in line
