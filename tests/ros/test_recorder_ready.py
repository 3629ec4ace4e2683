"""The recorder says whether it has matched every publisher a run will record from."""

from __future__ import annotations

import subprocess

import pytest

from tests.conftest import REPO
from tests.ros.graph_client import GraphClient

pytestmark = pytest.mark.ros


def test_recorder_is_ready_only_once_it_hears_the_publishers(ros_processes, rclpy_context,
                                                             tmp_path):
    from sgim_msgs.msg import Competence
    from sgim_msgs.srv import RecorderReady
    from sgim_ros import qos

    ros_processes.start("recorder", [str(REPO / "ros_ws" / "ros2run.sh"), "sgim_nodes",
                                     "recorder", "--ros-args", "-p",
                                     f"output:={tmp_path / 'bag'}"])
    client = GraphClient(rclpy_context, "readiness")
    try:
        ready = client.node.create_client(RecorderReady, "/recorder_ready")
        assert ready.wait_for_service(timeout_sec=30)
        ask = RecorderReady.Request(topics=["competences"], publishers=[1])
        first = client.ask(ready, ask)
        assert not first.ready and "competences (0/1)" in first.message
        client.node.create_publisher(Competence, "/competences", qos.RECORDS)
        assert client.spin_until(lambda: client.ask(ready, ask).ready, timeout=30)
    finally:
        client.close()


class _Sub:
    def __init__(self, matched: int) -> None:
        self.matched = matched

    def get_publisher_count(self) -> int:
        return self.matched


def test_a_listener_is_unready_only_on_its_own_topics_that_lack_a_match():
    from sgim_ros.ready import unmatched

    subs = {"movements": _Sub(1), "run_status": _Sub(0), "markers/landings": _Sub(2)}
    topics = ["movements", "run_status", "goals", "markers/landings"]
    assert unmatched(subs, topics, [1, 1, 7, 2]) == ["run_status (0/1)"]  # goals: not its own
    assert unmatched(subs, topics, [2, 0, 0, 3]) == ["movements (1/2)",
                                                    "markers/landings (2/3)"]
    assert unmatched(subs, topics, [0, 0, 0, 0]) == []


def test_the_evaluator_is_ready_only_once_it_hears_the_movements(ros_processes, rclpy_context):
    """The arbiter asks evaluator_ready before its first movement (a resumed run's evaluator
    once missed movements published before its match, and never evaluated again)."""
    from sgim_msgs.msg import Movement
    from sgim_msgs.srv import RecorderReady
    from sgim_ros import qos

    ros_processes.start("evaluator", [str(REPO / "ros_ws" / "ros2run.sh"), "sgim_nodes",
                                      "evaluator"])
    client = GraphClient(rclpy_context, "readiness")
    try:
        ready = client.node.create_client(RecorderReady, "/evaluator_ready")
        assert ready.wait_for_service(timeout_sec=60)
        ask = RecorderReady.Request(topics=["movements", "goals"], publishers=[1, 3])
        first = client.ask(ready, ask)
        assert not first.ready and first.message == "not yet matched: movements (0/1)"
        client.node.create_publisher(Movement, "/movements", qos.RECORDS)
        assert client.spin_until(lambda: client.ask(ready, ask).ready, timeout=30)
    finally:
        client.close()


def test_the_simulator_serves_only_once_every_named_listener_hears_it(ros_processes,
                                                                       rclpy_context):
    """At its start and after a restart, sim_bridge holds execute_action back until every
    node of `movement_listeners` is discovered and matched on `movements`."""
    from sgim_msgs.msg import Movement
    from sgim_msgs.srv import ExecuteAction
    from sgim_ros import qos

    ros_processes.start("sim_bridge", [
        str(REPO / "ros_ws" / "ros2run.sh"), "sim_bridge", "sim_bridge", "--ros-args",
        "-p", "wait_for_recorder:=true", "-p", "movement_listeners:=recorder,evaluator"])
    recorder = GraphClient(rclpy_context, "recorder")
    evaluator = None
    try:
        heard = recorder.node.create_subscription(Movement, "/movements", lambda _: None,
                                                  qos.RECORDS)
        execute = recorder.node.create_client(ExecuteAction, "/execute_action")
        # The simulator is up and the recorder hears it; the evaluator is still missing.
        assert recorder.spin_until(lambda: heard.get_publisher_count() >= 1, timeout=60)
        assert not execute.wait_for_service(timeout_sec=4.0)
        evaluator = GraphClient(rclpy_context, "evaluator")
        evaluator.node.create_subscription(Movement, "/movements", lambda _: None,
                                           qos.RECORDS)
        assert execute.wait_for_service(timeout_sec=60)
    finally:
        recorder.close()
        if evaluator is not None:
            evaluator.close()


def test_the_arbiter_makes_no_movement_before_every_listener_is_ready(ros_processes,
                                                                      rclpy_context):
    """A stand-in evaluator that says "not yet" for its first 5 s: the arbiter's first
    movement comes after its first "ready", whatever the discovery timing."""
    import time

    from sgim_msgs.msg import Evaluation, Movement
    from sgim_msgs.srv import RecorderReady
    from sgim_ros import qos

    ros_processes.start("sim_bridge", [str(REPO / "ros_ws" / "ros2run.sh"), "sim_bridge",
                                       "sim_bridge"])
    client = GraphClient(rclpy_context, "evaluator")
    node = client.node
    seen: list[tuple[int, float]] = []
    answers: list[tuple[bool, float]] = []
    opens_at: list[float] = []
    evaluations = node.create_publisher(Evaluation, "/evaluations", qos.RECORDS)
    node.create_subscription(Movement, "/movements",
                             lambda m: seen.append((m.index, time.monotonic())), qos.RECORDS)

    def answer(request, response):
        opens_at or opens_at.append(time.monotonic() + 5.0)
        response.ready = time.monotonic() >= opens_at[0]
        response.message = "" if response.ready else "not yet matched: movements (0/1)"
        answers.append((response.ready, time.monotonic()))
        return response

    node.create_service(RecorderReady, "/evaluator_ready", answer)
    arbiter = ros_processes.start("arbiter", [
        str(REPO / "ros_ws" / "ros2run.sh"), "sgim_nodes", "social_interaction", "--ros-args",
        "-p", "learner:=random", "-p", "movements:=5", "-p", "wait_for_recorder:=false",
        "-p", "settle_time:=0.0", "-p", "startup_timeout:=60.0"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        assert client.spin_until(lambda: len(seen) >= 5 or arbiter.poll() is not None,
                                 timeout=120), "no movements"
        evaluations.publish(Evaluation(movement_index=5, mean_distance=0.1, outcome_size=2,
                                       goals=[0.0, 0.0], reached=[0.1, 0.0], distances=[0.1]))
        output, _ = arbiter.communicate(timeout=60)
    finally:
        client.close()
    assert arbiter.returncode == 0, output
    first_ready = min(t for ready, t in answers if ready)
    assert any(not ready for ready, _ in answers), "the arbiter never met a 'not yet'"
    assert [i for i, _ in seen] == [1, 2, 3, 4, 5]
    assert seen[0][1] >= first_ready, (seen[0][1] - first_ready)
