"""The harness's own guarantees: distinct domains, local discovery, no process left behind."""

from __future__ import annotations

import os
import signal
import sys
import time

import pytest

from sgim_nodes.graph.domain import isolated_ros_environment, reserve_domain
from sgim_nodes.graph.processes import ProcessGroup, group_is_empty


def test_reservations_never_share_a_domain():
    with reserve_domain() as first, reserve_domain(preferred=first.domain_id) as second:
        assert second.domain_id != first.domain_id
    # Released: the same id can be had again.
    with reserve_domain(preferred=first.domain_id) as again:
        assert again.domain_id == first.domain_id


def test_bad_preferred_domain_is_refused():
    with pytest.raises(ValueError, match=r"0\.\.232"):
        reserve_domain(preferred=500)


def test_isolated_environment_keeps_discovery_on_this_host():
    env = isolated_ros_environment(42, {"ROS_LOCALHOST_ONLY": "0", "PATH": "/bin"})
    assert env["ROS_DOMAIN_ID"] == "42"
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert "ROS_LOCALHOST_ONLY" not in env and env["PATH"] == "/bin"
    # A user who asks for more keeps it.
    wide = isolated_ros_environment(3, {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"})
    assert wide["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "SUBNET"


STUBBORN = """
import os, signal, subprocess, sys, time
signal.signal(signal.SIGINT, signal.SIG_IGN)
signal.signal(signal.SIGTERM, signal.SIG_IGN)
GRANDCHILD = "import signal, time; signal.signal(signal.SIGINT, signal.SIG_IGN); time.sleep(60)"
subprocess.Popen([sys.executable, "-c", GRANDCHILD])
print("up", flush=True)
time.sleep(60)
"""


def test_process_group_stops_children_that_ignore_signals(tmp_path):
    group = ProcessGroup(env=dict(os.environ), log_dir=tmp_path)
    child = group.start("stubborn", [sys.executable, "-c", STUBBORN])
    deadline = time.monotonic() + 20
    while "up" not in (tmp_path / "stubborn.log").read_text() and time.monotonic() < deadline:
        time.sleep(0.05)
    start = time.monotonic()
    codes = group.stop_all(grace=0.5)
    assert codes == [-signal.SIGKILL]
    assert group_is_empty(child.pid), "the grandchild survived"
    assert time.monotonic() - start < 10


def test_process_group_lets_a_clean_child_exit_on_sigint():
    with ProcessGroup() as group:
        child = group.start("sleeper", [sys.executable, "-c", "import time; time.sleep(60)"])
        time.sleep(0.3)
    assert child.returncode is not None and child.returncode != -signal.SIGKILL
