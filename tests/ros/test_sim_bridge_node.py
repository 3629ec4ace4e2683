"""The sim_bridge node over ROS, from another process: results, records, bad input."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

from tests.conftest import ROS2RUN
from tests.ros.graph_client import GraphClient

pytestmark = pytest.mark.ros

SEED = 5


@pytest.fixture
def client(rclpy_context):
    c = GraphClient(rclpy_context)
    yield c
    c.close()


@pytest.fixture
def sim_node(ros_processes):
    return ros_processes.start(
        "sim_bridge",
        [ROS2RUN, "sim_bridge", "sim_bridge", "--ros-args", "-p", f"seed:={SEED}"],
    )


def _actions(n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(11)
    return [rng.uniform(-1.0, 1.0, 24) for _ in range(n)]


def test_service_matches_the_world_in_process_and_records_movements(sim_node, client):
    from sgim_msgs.msg import Movement
    from sgim_msgs.srv import ExecuteAction
    from sgim_ros import qos
    from sim_bridge.fishing_world import FishingWorld

    movements = client.capture(Movement, "/movements", qos.RECORDS)
    service = client.node.create_client(ExecuteAction, "/execute_action")
    assert service.wait_for_service(timeout_sec=30), "sim_bridge did not come up"
    assert client.spin_until(lambda: client.node.count_publishers("/movements") > 0)

    # The first reply right after discovery can be lost (GraphClient.try_call): a refused
    # action, which moves nothing, is asked until one comes, before the movements that count.
    refused = client.ask(service, ExecuteAction.Request(action=[0.0] * 5, record=True))
    assert refused.status == Movement.STATUS_INVALID_ACTION

    reference = FishingWorld(seed=SEED)
    actions = _actions(4)
    for k, action in enumerate(actions, start=1):
        request = ExecuteAction.Request(
            action=action.tolist(),
            process=Movement.PROCESS_RANDOM,
            movement_index=k,
            goal=[0.5, -0.5],
            goal_index=k + 100,
            record=k != 4,  # the last one is executed but not recorded
        )
        response = client.call(service, request)
        expected = reference.execute(action)
        assert response.status == int(expected.status)
        if expected.outcome is None:
            assert len(response.outcome) == 0
        else:  # the node adds nothing: same seed, same outcome, bit for bit
            assert np.array_equal(np.asarray(response.outcome), expected.outcome)
    reference.close()

    assert client.spin_until(lambda: len(movements) == 3)
    client.spin_for(0.5)
    assert [m.index for m in movements] == [1, 2, 3]
    for m, action in zip(movements, actions, strict=False):
        assert np.array_equal(np.asarray(m.action), action)
        assert m.process == Movement.PROCESS_RANDOM and list(m.goal) == [0.5, -0.5]
        assert m.goal_index == m.index + 100
        assert (len(m.outcome) == 2) == (m.status == Movement.STATUS_OK)


@pytest.mark.parametrize(
    ("action", "reason"),
    [
        ([0.0] * 23, "24"),
        ([0.0] * 23 + [float("nan")], "NaN"),
        ([0.0] * 23 + [float("inf")], "infinite"),
        ([0.0] * 23 + [1.5], "[-1, 1]"),
    ],
)
def test_bad_actions_get_an_error_status_and_are_not_recorded(sim_node, client, action, reason):
    from sgim_msgs.msg import Movement
    from sgim_msgs.srv import ExecuteAction
    from sgim_ros import qos

    movements = client.capture(Movement, "/movements", qos.RECORDS)
    service = client.node.create_client(ExecuteAction, "/execute_action")
    assert service.wait_for_service(timeout_sec=30)
    # A refused action changes nothing, so it may be asked again (GraphClient.try_call).
    response = client.ask(service, ExecuteAction.Request(action=action, record=True))
    assert response.status == Movement.STATUS_INVALID_ACTION
    assert reason in response.message and len(response.outcome) == 0
    # The node survives and still serves good actions.
    good = client.ask(service, ExecuteAction.Request(action=[0.0] * 24, record=False))
    assert good.status != Movement.STATUS_INVALID_ACTION
    client.spin_for(0.5)
    assert movements == []


def test_bad_parameter_stops_the_node_with_a_clear_message(ros_processes):
    child = ros_processes.start(
        "sim_bridge_bad",
        [ROS2RUN, "sim_bridge", "sim_bridge", "--ros-args", "-p", "noise:=-0.5"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    output, _ = child.communicate(timeout=60)
    assert child.returncode == 2
    assert "noise" in output and ">= 0" in output
