"""The web teacher node in this process: what its page gets once the run's ROS context is
shut down and before its server stops (the page polls on through a node's teardown)."""

from __future__ import annotations

import http.client
import json
import time

import pytest

pytestmark = pytest.mark.ros


def _ask(port: int, method: str, path: str, body: bytes | None = None) -> tuple[int, dict]:
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        connection.request(method, path, body=body, headers={
            "X-Teacher": "1", "Content-Type": "application/json"})
        reply = connection.getresponse()
        return reply.status, json.loads(reply.read())
    finally:
        connection.close()


def test_requests_after_the_context_is_shut_down_get_a_clean_503(rclpy_context):
    from rclpy.parameter import Parameter

    from teacher.web.server import RUN_OVER
    from teacher.web_teacher_node import WebTeacherNode

    node = WebTeacherNode(context=rclpy_context, parameter_overrides=[
        Parameter("port", value=0), Parameter("render_casts", value=False)])
    try:
        port = node.server.port
        status, state = _ask(port, "GET", "/api/state?landings=0")
        assert status == 200 and state["count"] == 0
        rclpy_context.shutdown()  # what Ctrl-C or the launcher's SIGINT does first
        started = time.monotonic()
        answers = [_ask(port, "GET", "/api/state?landings=0"),
                   _ask(port, "GET", "/api/legend"),
                   _ask(port, "POST", "/api/command", b'{"command": "pace", "what": "pause"}')]
        assert answers == [(503, {"ok": False, "message": RUN_OVER})] * 3
        assert time.monotonic() - started < 2.0  # a command is not left waiting its time out
        # Without the flag (a request racing the shutdown), the node's own check says it.
        node.server.over = ""
        assert _ask(port, "GET", "/api/state?landings=0") == (503, {"ok": False,
                                                                    "message": RUN_OVER})
    finally:
        node.destroy_node()
