"""Parameters as ROS expects them: read-only where they shape the run, checked on change,
ranges in the descriptors; and a node that refuses what it would otherwise silently ignore."""

from __future__ import annotations

import subprocess

import pytest

from tests.conftest import ROS2RUN
from tests.ros.graph_client import GraphClient

pytestmark = pytest.mark.ros


def _set(client, node: str, **values):
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    service = client.node.create_client(SetParameters, f"/{node}/set_parameters")
    assert service.wait_for_service(timeout_sec=60), f"{node} did not come up"
    request = SetParameters.Request(parameters=[
        Parameter(name=name, value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE,
                                                  double_value=value))
        for name, value in values.items()])
    return client.ask(service, request).results


def _get(client, node: str, name: str):
    from rcl_interfaces.srv import DescribeParameters, GetParameters

    get = client.node.create_client(GetParameters, f"/{node}/get_parameters")
    describe = client.node.create_client(DescribeParameters, f"/{node}/describe_parameters")
    assert get.wait_for_service(timeout_sec=60) and describe.wait_for_service(timeout_sec=60)
    value = client.ask(get, GetParameters.Request(names=[name])).values[0]
    descriptor = client.ask(describe, DescribeParameters.Request(names=[name])).descriptors[0]
    return value, descriptor


def test_set_parameters_refuses_read_only_and_out_of_range_values(ros_processes,
                                                                   rclpy_context):
    ros_processes.start("sim", [ROS2RUN, "sim_bridge", "sim_bridge"])
    ros_processes.start("explorer", [ROS2RUN, "sgim_nodes", "low_level_explorer"])
    client = GraphClient(rclpy_context, "param_setter")
    try:
        # The physics of a run cannot change while it runs.
        [result] = _set(client, "sim_bridge", noise=-1.0)
        assert not result.successful and "read-only" in result.reason
        [result] = _set(client, "sim_bridge", noise=0.01)
        assert not result.successful and "read-only" in result.reason
        value, descriptor = _get(client, "sim_bridge", "noise")
        assert value.double_value == pytest.approx(0.0042) and descriptor.read_only
        assert descriptor.floating_point_range[0].from_value == 0.0
        # A timeout may change, but only to a valid value, and then it applies.
        [result] = _set(client, "low_level_explorer", service_timeout=-1.0)
        assert not result.successful and "out of range" in result.reason  # the descriptor
        [result] = _set(client, "low_level_explorer", service_timeout=0.0)
        assert not result.successful and "must be > 0" in result.reason  # the node's check
        [result] = _set(client, "low_level_explorer", service_timeout=5.0)
        assert result.successful, result.reason
        value, descriptor = _get(client, "low_level_explorer", "service_timeout")
        assert value.double_value == 5.0 and not descriptor.read_only
        [result] = _set(client, "low_level_explorer", alpha=0.3)
        assert not result.successful and "read-only" in result.reason
        _, descriptor = _get(client, "low_level_explorer", "goal_budget")
        assert descriptor.read_only and descriptor.integer_range[0].from_value == 1
    finally:
        client.close()


@pytest.mark.parametrize(("args", "file_text", "expected"), [
    (["-p", "noize:=0.1"], None, "unknown parameter 'noize' (-p noize:=0.1)"),
    (["--params-file", "{file}"], "sim_bridge:\n  ros__parameters:\n    noize: 0.1\n",
     "unknown parameter 'noize' (section sim_bridge of"),
    (["--params-file", "{file}"], '"just a string"\n', "it holds a str"),
    (["--params-file", "{file}"], "- 1\n", "it holds a list"),
    (["-p", "noise:=[1,"], None, "Couldn't parse parameter override rule"),
])
def test_a_node_refuses_parameters_it_would_ignore(ros_processes, tmp_path, args, file_text,
                                                   expected):
    path = tmp_path / "params.yaml"
    if file_text is not None:
        path.write_text(file_text)
    argv = [ROS2RUN, "sim_bridge", "sim_bridge", "--ros-args",
            *(a.format(file=path) for a in args)]
    child = ros_processes.start("sim-bad", argv, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
    output, _ = child.communicate(timeout=60)
    assert child.returncode == 2, output
    assert expected in output and "Traceback" not in output


def test_a_wildcard_section_may_hold_other_nodes_parameters(ros_processes, tmp_path,
                                                             rclpy_context):
    """The run scripts give every node one /** file: a node reads what it declares there."""
    path = tmp_path / "params.yaml"
    path.write_text("/**:\n  ros__parameters:\n    goal_budget: 3\n    noise: 0.001\n")
    ros_processes.start("sim-wildcard", [ROS2RUN, "sim_bridge", "sim_bridge", "--ros-args",
                                         "--params-file", str(path)])
    client = GraphClient(rclpy_context, "param_reader")
    try:
        value, _ = _get(client, "sim_bridge", "noise")
        assert value.double_value == 0.001
    finally:
        client.close()
