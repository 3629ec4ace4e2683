"""The harness's own guarantees: distinct domains, local discovery, no process left behind."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from sgim_nodes.graph.domain import (
    DomainInUse,
    hold_run_domain,
    isolated_ros_environment,
    reserve_domain,
)
from sgim_nodes.graph.processes import ProcessGroup, group_is_empty


def test_reservations_never_share_a_domain():
    with reserve_domain() as first, reserve_domain(preferred=first.domain_id) as second:
        assert second.domain_id != first.domain_id
    # Released: the same id can be had again.
    with reserve_domain(preferred=first.domain_id) as again:
        assert again.domain_id == first.domain_id


def test_a_run_holds_its_domain_whoever_chose_it():
    """One run per domain: a second run naming it is refused in one line, a run that picks
    its own never takes it, and a domain a caller reserved can be lent to one run."""
    with hold_run_domain() as first:
        with pytest.raises(DomainInUse, match=rf"^ROS domain {first.domain_id} is held by "
                                              r"another run on this host: leave out --domain"):
            hold_run_domain(first.domain_id)
        with hold_run_domain() as second:
            assert second.domain_id != first.domain_id
    with reserve_domain() as lent:  # a test session's domain, named by its runs' --domain
        with hold_run_domain(lent.domain_id) as run:
            assert run.domain_id == lent.domain_id
            with pytest.raises(DomainInUse):
                hold_run_domain(lent.domain_id)
            with reserve_domain(preferred=lent.domain_id) as other:
                assert other.domain_id != lent.domain_id
        with hold_run_domain(lent.domain_id) as next_run:  # released: the next run may
            assert next_run.domain_id == lent.domain_id
    with hold_run_domain(first.domain_id) as named, hold_run_domain() as picked, \
            reserve_domain(preferred=named.domain_id) as pool:  # a named one leaves the pool
        assert named.domain_id not in (picked.domain_id, pool.domain_id)


def test_a_run_s_domain_is_held_by_any_process_that_inherited_it():
    held = hold_run_domain()
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"],
                             pass_fds=held.fds)
    try:
        held.release()
        with pytest.raises(DomainInUse):
            hold_run_domain(held.domain_id)
    finally:
        child.kill()
        child.wait()
    with hold_run_domain(held.domain_id) as again:
        assert again.domain_id == held.domain_id


def test_bad_preferred_domain_is_refused():
    with pytest.raises(ValueError, match=r"0\.\.232"):
        reserve_domain(preferred=500)


def test_isolated_environment_keeps_discovery_on_this_host():
    env = isolated_ros_environment(42, {"ROS_LOCALHOST_ONLY": "0", "PATH": "/bin"})
    assert env["ROS_DOMAIN_ID"] == "42"
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert "ROS_LOCALHOST_ONLY" not in env and env["PATH"] == "/bin"
    # On this host alone, Fast DDS talks over shared memory only.
    assert env["FASTDDS_BUILTIN_TRANSPORTS"] == "SHM"
    # A user who asks for more keeps it, and the transports that reach it.
    wide = isolated_ros_environment(3, {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"})
    assert wide["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "SUBNET"
    assert "FASTDDS_BUILTIN_TRANSPORTS" not in wide
    own = isolated_ros_environment(3, {"FASTDDS_BUILTIN_TRANSPORTS": "UDPv4"})
    assert own["FASTDDS_BUILTIN_TRANSPORTS"] == "UDPv4"


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


OWNER = """
import sys, time
from sgim_nodes.graph.processes import ProcessGroup
group = ProcessGroup()
child = group.start("node", [sys.executable, "-c", sys.argv[1]])
print(child.pid, flush=True)
time.sleep(600)
"""

FOLLOWER = """
import signal, sys, time
from sgim_ros.entry import follow_launcher
if {ignore}:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
assert follow_launcher(grace=2.0)
print("following", flush=True)
try:
    time.sleep(600)
except KeyboardInterrupt:
    print("stopped cleanly", flush=True)
"""


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in ("Z", "X")


def _ends_within(pid: int, seconds: float = 30) -> bool:
    """Wait until the process is dead (or a zombie); False if it still lives after that."""
    deadline = time.monotonic() + seconds
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not _alive(pid)


@pytest.mark.ros
@pytest.mark.parametrize("ignores_sigint", [False, True])
def test_a_node_ends_when_its_launcher_is_killed(tmp_path, ignores_sigint):
    """SIGKILL leaves the launcher no chance to stop its nodes: they stop by themselves, on
    the parent-death signal, or hard after a grace period if they ignore it."""
    import subprocess

    owner = subprocess.Popen([sys.executable, "-c", OWNER,
                              FOLLOWER.format(ignore=ignores_sigint)],
                             stdout=subprocess.PIPE, text=True, start_new_session=True)
    try:
        pid = int(owner.stdout.readline())
        time.sleep(3.0)  # let it arm its signal and watchdog (python and rclpy imports)
        assert _alive(pid)
        os.kill(owner.pid, signal.SIGKILL)
        owner.wait(timeout=10)
        assert _ends_within(pid), "the node outlived its launcher"
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(owner.pid, signal.SIGKILL)


WATCHED_LAUNCHER = """
import signal, sys, time
from sgim_nodes.graph.supervise import watch_owner
def stop(signum, frame):
    print("stopping the run as on SIGTERM", flush=True)
    sys.exit(143)
signal.signal(signal.SIGTERM, stop)
watch_owner()
print("watching", flush=True)
time.sleep(600)
"""


@pytest.mark.ros
def test_a_launcher_stops_its_run_when_the_study_that_started_it_is_killed(tmp_path):
    """run_study.sh's launchers hold the read end of its lifeline: SIGKILL of the study
    closes it, and each launcher stops its run as on SIGTERM (and records it so)."""
    import subprocess

    log = tmp_path / "launcher.log"
    owner = subprocess.Popen([sys.executable, "-c", OWNER.replace(
        'child = group.start("node", [sys.executable, "-c", sys.argv[1]])',
        f'child = group.start("node", [sys.executable, "-c", sys.argv[1]], '
        f'stdout=open({str(log)!r}, "w"))'), WATCHED_LAUNCHER],
        stdout=subprocess.PIPE, text=True, start_new_session=True)
    pid = None
    try:
        pid = int(owner.stdout.readline())
        deadline = time.monotonic() + 30
        while "watching" not in log.read_text() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _alive(pid) and "watching" in log.read_text()
        os.kill(owner.pid, signal.SIGKILL)
        owner.wait(timeout=10)
        assert _ends_within(pid), "the launcher outlived its study"
        assert "stopping the run as on SIGTERM" in log.read_text()
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(owner.pid, signal.SIGKILL)
        if pid is not None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(pid, signal.SIGKILL)


STARTER = """
import os, sys
from sgim_ros.entry import follow_launcher
os.environ["SGIM_LAUNCHER_FD"] = sys.argv[1]
for _ in range(int(sys.argv[2])):
    assert follow_launcher(grace=600.0)
print("started", flush=True)
"""

# Another node of the same run, starting at the same moment: it shares the pipe's open file
# description, and with it the description's blocking flag, which it sets back to blocking.
OTHER_NODE = """
import os, sys
fd = int(sys.argv[1])
while True:
    os.set_blocking(fd, True)
"""


@pytest.mark.ros
def test_nodes_starting_together_never_block_on_their_shared_lifeline():
    """Every node of a run inherits the same read end of the launcher's pipe. Checking it for
    the launcher's death must not depend on the pipe's blocking flag, which the nodes share: a
    node that found the pipe blocking waited for the launcher's end instead of starting (seen:
    an evaluator that never started, and its run aborted after 60 s)."""
    read_end, write_end = os.pipe()
    other = subprocess.Popen([sys.executable, "-c", OTHER_NODE, str(read_end)],
                             pass_fds=(read_end,))
    try:
        child = subprocess.Popen([sys.executable, "-c", STARTER, str(read_end), "300"],
                                 pass_fds=(read_end,), stdout=subprocess.PIPE, text=True)
        try:
            out, _ = child.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            child.kill()
            child.communicate()
            pytest.fail("a check of the lifeline blocked while the launcher was alive")
        assert child.returncode == 0 and out.strip() == "started"
    finally:
        other.kill()
        other.wait()
        os.close(read_end)
        os.close(write_end)


QUICK_NODE = """
import atexit, os, sys
import rclpy.node
from sgim_ros.host import NodeEntry

class Done(rclpy.node.Node):
    def __init__(self):
        super().__init__("done_at_once")
        self.finished, self.exit_code = True, 3

atexit.register(lambda: print("finalized", flush=True))
if len(sys.argv) > 1:
    os.environ["SGIM_LAUNCHER_FD"] = sys.argv[1]
print("returned", NodeEntry(Done).main(["done_at_once"]), flush=True)
"""


@pytest.mark.ros
def test_a_node_of_a_run_ends_without_the_interpreters_finalization():
    """The middleware can spin forever in its destructors at exit, after the daemon threads
    (the launcher watchdog among them) are stopped: a node of a run then outlived its launcher
    and held the run's lock. A node started by the launcher ends right after its teardown, with
    its exit code; one started alone finalizes as usual."""
    read_end, write_end = os.pipe()
    try:
        of_a_run = subprocess.run([sys.executable, "-c", QUICK_NODE, str(read_end)],
                                  pass_fds=(read_end,), capture_output=True, text=True,
                                  timeout=60)
        alone = subprocess.run([sys.executable, "-c", QUICK_NODE], capture_output=True,
                               text=True, timeout=60)
    finally:
        os.close(read_end)
        os.close(write_end)
    assert of_a_run.returncode == 3, of_a_run.stderr
    assert "finalized" not in of_a_run.stdout and "returned" not in of_a_run.stdout
    assert alone.returncode == 0 and "returned 3" in alone.stdout
    assert "finalized" in alone.stdout
