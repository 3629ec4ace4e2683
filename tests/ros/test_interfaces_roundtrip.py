"""Two separate processes exchange every custom message, call the service and the action."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.ros.graph_client import GraphClient
from tests.ros.interface_samples import filled, message_class, message_names

pytestmark = pytest.mark.ros

PEER = Path(__file__).resolve().parent / "peers" / "echo_peer.py"
TIMEOUT = 30.0  # s, for discovery and calls


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
    client = GraphClient(rclpy_context, "roundtrip_test")
    yield client.node, client.spin_until
    client.close()


def test_every_message_type_crosses_processes(peer, node):
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

    qos = QoSProfile(
        depth=10, history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE
    )
    node, spin_until = node
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
    matched = spin_until(
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
    assert spin_until(lambda: len(received) == len(names)), sorted(received)
    for name in names:
        assert received[name] == sent[name], f"{name} changed on the way"
        assert received[name] != message_class(name)(), f"{name} sample is all defaults"


def test_execute_action_service_across_processes(peer, node):
    from sgim_msgs.msg import Movement
    from sgim_msgs.srv import ExecuteAction

    node, spin_until = node
    client = node.create_client(ExecuteAction, "/roundtrip/execute_action")
    assert client.wait_for_service(timeout_sec=TIMEOUT)

    def call(action):
        future = client.call_async(ExecuteAction.Request(action=action, record=False))
        assert spin_until(future.done)
        return future.result()

    good = call([0.5] * 12 + [-0.25] * 12)
    assert good.status == Movement.STATUS_OK
    assert list(good.outcome) == pytest.approx([0.5, -0.25])
    bad = call([0.0] * 5)
    assert bad.status == Movement.STATUS_INVALID_ACTION
    assert "5" in bad.message and len(bad.outcome) == 0


def test_an_action_with_feedback_across_processes(peer, node):
    from rclpy.action import ActionClient

    from sgim_msgs.action import Imitate

    node, spin_until = node
    client = ActionClient(node, Imitate, "/roundtrip/imitate")
    assert client.wait_for_server(timeout_sec=TIMEOUT)
    feedback = []
    send = client.send_goal_async(
        Imitate.Goal(action=[0.2] * 24, outcome=[0.1, -0.3], repetitions=3,
                     movements_before=7),
        feedback_callback=lambda f: feedback.append(f.feedback.movements_done),
    )
    assert spin_until(send.done)
    handle = send.result()
    assert handle.accepted
    result_future = handle.get_result_async()
    assert spin_until(result_future.done)
    result = result_future.result().result
    assert list(result.best_outcome) == pytest.approx([0.1, -0.3])
    assert result.movements_used == 3 and result.best_distance == pytest.approx(0.25)
    assert feedback and feedback == sorted(feedback) and feedback[-1] <= 3


def test_the_cores_process_and_status_codes_are_the_messages():
    from sgim_msgs.msg import Movement
    from sgim_nodes.core.environment import PROCESS_CODES, Status
    from sim_bridge.fishing_world import Status as CastStatus

    for label, code in PROCESS_CODES.items():
        assert getattr(Movement, f"PROCESS_{label.upper()}") == code, label
    for status in (*Status, *CastStatus):  # the world cannot import the core: both are checked
        assert getattr(Movement, f"STATUS_{status.name}") == status.value, status.name
