"""Nodes sharing a process (sgim_ros/host.py, nodes/composed.py): each refuses its own bad
configuration, and a run whose shared process is killed fails naming it and resumes whole."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import time
from collections.abc import Iterator

import pytest
import yaml

from tests.conftest import REPO
from tests.ros.test_faults import find_process

pytestmark = pytest.mark.ros

ROS2RUN = str(REPO / "ros_ws" / "ros2run.sh")
RUN = str(REPO / "ros_ws" / "run_experiment.sh")
LIGHT = ["--node", "interest_computer=sgim_nodes.nodes.interest_computer",
         "--node", "markers=sgim_nodes.nodes.markers"]


@contextlib.contextmanager
def reaped(child: subprocess.Popen) -> Iterator[subprocess.Popen]:
    """The child's process group, killed on the way out if it still runs (a failed test)."""
    try:
        yield child
    finally:
        if child.poll() is None:
            os.killpg(child.pid, signal.SIGKILL)
            child.wait()


def interrupt(child: subprocess.Popen) -> None:
    """Ctrl-C to the child's process group, and its end awaited."""
    os.killpg(child.pid, signal.SIGINT)
    child.wait(timeout=30)


def composed(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run([ROS2RUN, "sgim_nodes", "composed", *args], capture_output=True,
                          text=True, timeout=timeout)


def test_a_member_with_a_parameter_it_does_not_declare_stops_the_process(ros_domain):
    done = composed("--process", "p", *LIGHT, "--ros-args", "-p", "markers:bogus:=1")
    assert done.returncode == 2, done.stderr
    assert "[p] [markers] unknown parameter 'bogus'" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_node_without_an_entry_is_refused_in_one_line(ros_domain):
    done = composed("--process", "p", "--node", "x=sgim_nodes.core.runner", *LIGHT)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "[p] --node 'x=sgim_nodes.core.runner': sgim_nodes.core.runner declares no node ENTRY "
        "(module 'sgim_nodes.core.runner' has no attribute 'ENTRY')"]
    twice = composed("--process", "p", *LIGHT, *LIGHT[:2])
    assert twice.returncode == 2 and "named twice" in twice.stderr


def test_sigint_ends_every_member_and_tells_their_ends(ros_domain, tmp_path):
    from sgim_ros.ends import EndsReader

    log = tmp_path / "p.log"
    read_end, write_end = os.pipe()
    with open(log, "w") as out:
        child = subprocess.Popen([ROS2RUN, "sgim_nodes", "composed", "--process", "p",
                                  "--ends-fd", str(write_end), *LIGHT], stdout=out,
                                 stderr=subprocess.STDOUT, start_new_session=True,
                                 pass_fds=(write_end,))
    os.close(write_end)
    ends = EndsReader(read_end)
    with reaped(child):
        deadline = time.monotonic() + 60
        while "publishing markers" not in log.read_text() and time.monotonic() < deadline:
            assert child.poll() is None, log.read_text()
            time.sleep(0.2)
        time.sleep(1.0)  # the last member built spins too
        assert ends.read() == {}
        interrupt(child)
    assert child.returncode == 0, log.read_text()
    assert ends.read() == {"interest_computer": 0, "markers": 0} and ends.closed


@pytest.mark.slow
def test_a_killed_shared_process_fails_the_run_naming_it_and_resume_finishes_it(
        ros_processes, ros_domain, tmp_path):
    from sgim_nodes.bag.reader import BagReadWarning, load_run
    from sgim_nodes.bag.resume import load_run_folder
    from sgim_nodes.graph.processes import run_node_pids
    from tests.golden_runs import bag_digest, runner_digest, runner_records
    from tests.ros.test_faults import recorded_movements

    run_dir = tmp_path / "observers-kill"
    common = ["--domain", str(ros_domain), "--quiet", "--timeout", "300"]
    child = ros_processes.start(
        "run-observers-kill",
        [RUN, "saggriac", "--seed", "4", "--movements", "300", "--eval-every", "0",
         "--runs-dir", str(tmp_path), "--name", "observers-kill", *common],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + 240
    while recorded_movements(run_dir / "bag") < 60 and time.monotonic() < deadline:
        assert child.poll() is None, child.communicate()[0][-3000:]
        time.sleep(0.5)
    pid = find_process("composed", "--process observers", str(run_dir / "params.yaml"))
    assert pid is not None, "the shared process was not found"
    os.kill(pid, signal.SIGKILL)
    output, _ = child.communicate(timeout=120)
    assert child.returncode == 1, output[-3000:]
    assert ("failed: process observers (recorder, markers, interest_computer) was killed by "
            "SIGKILL at movement") in output, output[-3000:]
    assert not run_node_pids(run_dir)
    meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())
    assert meta["outcome"].startswith("failed: process observers")

    resumed = subprocess.run([RUN, "--resume", str(run_dir), *common], capture_output=True,
                             text=True, timeout=400)
    assert resumed.returncode == 0, resumed.stdout[-3000:] + resumed.stderr[-3000:]
    run = load_run_folder(run_dir)
    assert [m.index for m in run.movements] == list(range(1, 301))
    # What the killed process let the recorder keep is the uninterrupted run's beginning (the
    # resumed part draws from restarted streams: docs/reliability.md).
    with pytest.warns(BagReadWarning, match="was not closed"):
        kept = load_run(run_dir / "bag").movements
    uninterrupted = [r for r in runner_records("saggriac", 4, movements=300, eval_every=0)
                     if r["type"] == "movement"]
    assert 0 < len(kept) < 300
    assert bag_digest(kept) == runner_digest(uninterrupted[:len(kept)])
    assert bag_digest(run.movements[:len(kept)]) == bag_digest(kept)


QUITTER = """
import sys
from rclpy.node import Node
from sgim_ros.host import Member, NodeEntry, run_nodes

class Quitter(Node):  # ends by itself, failed, half a second after it starts
    def __init__(self, **options):
        super().__init__("quitter", **options)
        self.finished, self.exit_code = False, 0
        self.create_timer(0.5, self.quit)

    def quit(self):
        self.finished, self.exit_code = True, 3

class Stayer(Node):  # spins until shut down
    def __init__(self, **options):
        super().__init__("stayer", **options)
        self.create_timer(0.1, lambda: None)

fd = int(sys.argv[1]) if len(sys.argv) > 1 else None
raise SystemExit(run_nodes("p", [Member("quitter", NodeEntry(Quitter)),
                                 Member("stayer", NodeEntry(Stayer))], ["p"], fd))
"""


def test_a_failed_member_ends_its_process_only_when_no_ends_pipe_tells_of_it(ros_domain):
    """Under `ros2 launch`, which sees processes only, a member's failure must end its
    process; under the run launcher, which reads the ends pipe, the others go on."""
    import sys

    alone = subprocess.run([sys.executable, "-c", QUITTER], capture_output=True, text=True,
                           timeout=60)
    assert alone.returncode == 3, alone.stderr
    assert "[p] quitter failed (exit 3): the process ends" in alone.stderr

    from sgim_ros.ends import EndsReader

    read_end, write_end = os.pipe()
    child = subprocess.Popen([sys.executable, "-c", QUITTER, str(write_end)],
                             stderr=subprocess.PIPE, text=True, pass_fds=(write_end,),
                             start_new_session=True)
    os.close(write_end)
    ends = EndsReader(read_end)
    with reaped(child):
        deadline = time.monotonic() + 60
        while ends.read() == {} and time.monotonic() < deadline:
            assert child.poll() is None
            time.sleep(0.1)
        assert ends.read() == {"quitter": 3}
        time.sleep(1.0)
        assert child.poll() is None  # the stayer spins on
        interrupt(child)
    assert child.returncode == 3
    assert ends.read() == {"quitter": 3, "stayer": 0}
