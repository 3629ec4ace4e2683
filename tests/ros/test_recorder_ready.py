"""The recorder says whether it has matched every publisher a run will record from."""

from __future__ import annotations

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
        first = client.call(ready, ask)
        assert not first.ready and "competences (0/1)" in first.message
        client.node.create_publisher(Competence, "/competences", qos.RECORDS)
        assert client.spin_until(lambda: client.call(ready, ask).ready, timeout=30)
    finally:
        client.close()
