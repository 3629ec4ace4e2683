"""Faults during a run: a simulator that dies mid-run loses no movement and doubles none."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import pytest
import yaml

from tests.conftest import REPO

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")


@contextlib.contextmanager
def _no_warning():
    yield


def find_process(*parts: str) -> int | None:
    """The pid whose command line holds every one of `parts`."""
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            text = cmdline.read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if all(part in text for part in parts):
            return int(cmdline.parent.name)
    return None


def recorded_movements(bag: Path) -> int:
    """The highest movement a bag's finished parts hold (the open one is skipped)."""
    from sgim_nodes.bag.reader import read_messages

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return max((m.index for _, _, m in read_messages(bag, ["movements"])), default=0)
        except Exception:  # no finished part yet
            return 0


def test_a_killed_simulator_is_restarted_and_no_movement_is_lost_or_doubled(
        ros_processes, ros_domain, tmp_path, rclpy_context):
    from sgim_msgs.msg import Movement
    from sgim_nodes.bag.reader import load_run
    from sgim_ros import qos
    from tests.ros.graph_client import GraphClient

    client = GraphClient(rclpy_context, "fault_injector")
    seen = client.capture(Movement, "/movements", qos.RECORDS)
    child = ros_processes.start(
        "run-sim-kill",
        [RUN, "saggriac", "--seed", "4", "--movements", "200", "--eval-every", "0",
         "--runs-dir", str(tmp_path), "--name", "sim-kill", "--domain", str(ros_domain),
         "--quiet", "--timeout", "240", "--param", "service_timeout=2.0"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    params = str(tmp_path / "sim-kill" / "params.yaml")
    assert client.spin_until(lambda: len(seen) >= 100, timeout=120)
    pid = find_process("lib/sim_bridge/sim_bridge", params)
    assert pid is not None, "sim_bridge process not found"
    # Closed first: destroying the client's node deletes its DDS participant, and that once
    # crashed (SIGSEGV in rcl's node teardown) right after a peer of the domain was killed.
    client.close()
    os.kill(pid, signal.SIGKILL)
    output, _ = child.communicate(timeout=300)
    assert child.returncode == 0, output[-3000:]
    assert "restarting" in output

    from sgim_nodes.bag.reader import read_messages

    raw = [m.index for topic, _, m in read_messages(tmp_path / "sim-kill" / "bag",
                                                  ["movements"])]
    with pytest.warns(UserWarning, match="re-executed") if len(raw) > 200 else _no_warning():
        run = load_run(tmp_path / "sim-kill" / "bag")
    # Every movement once, in order: a movement the dying simulator recorded but never
    # answered was executed again, and only that later record counts.
    assert [m.index for m in run.movements] == list(range(1, 201))
    assert len(raw) - 200 <= 1 and raw[-1] == 200
    meta = yaml.safe_load((tmp_path / "sim-kill" / "metadata.yaml").read_text())
    assert meta["restarts"] == {"sim_bridge": 1} and meta["outcome"] == "finished"
    # And they are the uninterrupted run's: the restarted simulator casts movement k with the
    # k-th noise of its seed (sim_bridge/noise_cursor.py), not its stream's first.
    from tests.golden_runs import bag_digest, runner_digest, runner_records

    assert bag_digest(run.movements) == runner_digest(
        runner_records("saggriac", 4, movements=200, eval_every=0))


def test_an_interrupted_run_resumes_from_its_recording_to_the_same_final_count(
        ros_processes, ros_domain, tmp_path, rclpy_context):
    """Interrupted where it cannot have finished, whatever the machine's load: the teacher
    never answers turn 100 (its node is replaced by a sleeper; this test gives turn 0's
    word), so the arbiter waits at movement 100, and Ctrl-C comes once the bag holds it."""
    from sgim_msgs.msg import Demonstration, Movement, RunStatus, TeacherCheck
    from sgim_nodes.bag.resume import load_run_folder, segments
    from sgim_ros import qos
    from sgim_ros.interfaces import serves
    from sgim_ros.ready import serve_ready
    from tests.ros.graph_client import GraphClient

    # This test stands in for the teacher: named like it, it hears the movements (the
    # simulator waits for every listener of the graph), answers teacher_ready and publishes
    # on teacher_checks (the arbiter waits for that publisher before movement 0).
    client = GraphClient(rclpy_context, "teacher")
    status: list = []
    serve_ready(client.node, serves("teacher_ready"), {
        "run_status": client.node.create_subscription(RunStatus, "/run_status", status.append,
                                                      qos.RECORDS),
        "movements": client.node.create_subscription(Movement, "/movements", lambda _: None,
                                                     qos.RECORDS)})
    words = client.node.create_publisher(Demonstration, "/demonstrations", qos.RECORDS)
    client.node.create_publisher(TeacherCheck, "/teacher_checks", qos.RECORDS)  # kept by the node
    common = ["--domain", str(ros_domain), "--quiet", "--timeout", "600"]
    silent_teacher = f"teacher={sys.executable} -c 'import time; time.sleep(3600)'"
    first = ros_processes.start(
        "run-interrupted",
        [RUN, "sgim-d", "--seed", "5", "--movements", "200", "--eval-every", "100",
         "--demonstration-period", "100", "--runs-dir", str(tmp_path), "--name", "cut", *common,
         "--param", "teacher_timeout=600.0", "--prefix", silent_teacher],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    # The arbiter and the recorder hear the word; the run has started.
    assert client.spin_until(lambda: words.get_subscription_count() >= 2 and status,
                             timeout=180)
    cut = tmp_path / "cut"
    from sgim_ros.record_key import read_key, sign_teaching

    words.publish(sign_teaching("demonstrations", Demonstration(  # signed as the teacher signs
        stamp=client.node.get_clock().now().to_msg(), movement_index=0, teaching_set_index=-1,
        source="automatic"), read_key(cut)))  # the teacher's "nothing to show"

    deadline = time.monotonic() + 300
    while recorded_movements(cut / "bag") < 100:
        assert time.monotonic() < deadline and first.poll() is None, "the run did not reach 100"
        client.spin_for(0.5)
    first.send_signal(signal.SIGINT)  # Ctrl-C
    output, _ = first.communicate(timeout=120)
    client.close()
    assert first.returncode == 130, output[-3000:]
    before = load_run_folder(cut)
    assert [m.index for m in before.movements] == list(range(1, 101))

    second = ros_processes.start("run-resumed", [RUN, "--resume", str(cut), *common],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output, _ = second.communicate(timeout=600)
    assert second.returncode == 0, output[-3000:]
    assert [p.name for p in segments(cut)] == ["bag", "bag.resume1"]
    run = load_run_folder(cut)
    assert [m.index for m in run.movements] == list(range(1, 201))
    assert {0, 100, 200} <= {e.movement_index for e in run.evaluations}
    turns = [d.movement_index for d in run.demonstrations]
    assert sorted(turns) == [0, 100] and len(set(turns)) == 2  # no turn given twice
    meta = yaml.safe_load((cut / "metadata.yaml").read_text())
    assert meta["outcome"] == "finished" and len(meta["resumed"]) == 1
    # The resumed recorder validated its segment from the run's count, not from movement 0.
    assert meta["quarantine"]["total"] == 0, meta["quarantine"]
