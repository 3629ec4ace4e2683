"""Two separate processes exchange every custom message, call the service and the action."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.ros.interface_samples import filled, message_class, message_names

pytestmark = pytest.mark.ros

PEER = Path(__file__).resolve().parent / "peers" / "echo_peer.py"
TIMEOUT = 30.0


def _spin_until(executor, condition, timeout: float = TIMEOUT) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        executor.spin_once(timeout_sec=0.05)
    return condition()


@pytest.fixture
def peer(ros_processes):
    child = ros_processes.start(
        "echo_peer", [sys.executable, str(PEER)], stdout=subprocess.PIPE, text=True
    )
    line = child.stdout.readline()
    assert line.strip() == "READY", f"peer did not start: {line!r}"
    return child


@pytest.fixture
def node(rclpy_context):
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node

    node = Node("roundtrip_test", context=rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    yield node, executor
    executor.shutdown()
    node.destroy_node()


def test_every_message_type_crosses_processes(peer, node):
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

    qos = QoSProfile(
        depth=10, history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE
    )
    node, executor = node
    names = message_names()
    assert len(names) >= 7, names
    received: dict[str, object] = {}
    publishers = {}
    for name in names:
        cls = message_class(name)
        publishers[name] = node.create_publisher(cls, f"/roundtrip/in/{name}", qos)
        node.create_subscription(
            cls, f"/roundtrip/out/{name}", lambda m, n=name: received.setdefault(n, m), qos
        )
    # Wait on graph state, never on a fixed sleep: both directions matched for every type.
    matched = _spin_until(
        executor,
        lambda: all(
            p.get_subscription_count() > 0 and node.count_publishers(f"/roundtrip/out/{n}") > 0
            for n, p in publishers.items()
        ),
    )
    assert matched, "the peer's endpoints were not discovered"
    sent = {}
    for seed, name in enumerate(names, start=1):
        sent[name] = filled(message_class(name), seed)
        publishers[name].publish(sent[name])
    assert _spin_until(executor, lambda: len(received) == len(names)), sorted(received)
    for name in names:
        assert received[name] == sent[name], f"{name} changed on the way"
        assert received[name] != message_class(name)(), f"{name} sample is all defaults"


def test_execute_action_service_across_processes(peer, node):
    from sgim_msgs.msg import Movement
    from sgim_msgs.srv import ExecuteAction

    node, executor = node
    client = node.create_client(ExecuteAction, "/roundtrip/execute_action")
    assert client.wait_for_service(timeout_sec=TIMEOUT)

    def call(action):
        future = client.call_async(ExecuteAction.Request(action=action, record=False))
        assert _spin_until(executor, future.done)
        return future.result()

    good = call([0.5] * 12 + [-0.25] * 12)
    assert good.status == Movement.STATUS_OK
    assert list(good.outcome) == pytest.approx([0.5, -0.25])
    bad = call([0.0] * 5)
    assert bad.status == Movement.STATUS_INVALID_ACTION
    assert "5" in bad.message and len(bad.outcome) == 0


def test_reach_goal_action_across_processes(peer, node):
    from rclpy.action import ActionClient

    from sgim_msgs.action import ReachGoal

    node, executor = node
    client = ActionClient(node, ReachGoal, "/roundtrip/reach_goal")
    assert client.wait_for_server(timeout_sec=TIMEOUT)
    feedback = []
    send = client.send_goal_async(
        ReachGoal.Goal(goal=[0.1, -0.3], goal_index=7, max_movements=3),
        feedback_callback=lambda f: feedback.append(f.feedback.movements_done),
    )
    assert _spin_until(executor, send.done)
    handle = send.result()
    assert handle.accepted
    result_future = handle.get_result_async()
    assert _spin_until(executor, result_future.done)
    result = result_future.result().result
    assert list(result.reached) == pytest.approx([0.1, -0.3])
    assert result.movements_used == 3 and result.competence == pytest.approx(-0.25)
    assert feedback and feedback == sorted(feedback) and feedback[-1] <= 3
