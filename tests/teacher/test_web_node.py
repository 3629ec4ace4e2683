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


def test_the_page_takes_only_movements_the_run_signed(rclpy_context, monkeypatch):
    """A forged movement (unsigned, a huge index) reaches neither the page's count nor its
    picture, so it is never offered as a demonstration; the simulator's next one is."""
    import numpy as np
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.parameter import Parameter

    from sgim_msgs.msg import Movement
    from sgim_ros import qos, record_key
    from teacher.web_teacher_node import WebTeacherNode

    key = record_key.new_key()
    monkeypatch.setenv(record_key.ENV, key)  # what the launcher gives every node
    node = WebTeacherNode(context=rclpy_context, parameter_overrides=[
        Parameter("port", value=0), Parameter("render_casts", value=False)])
    rogue = Node("rogue", context=rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    executor.add_node(rogue)
    try:
        out = rogue.create_publisher(Movement, "/movements", qos.RECORDS)

        def movement(index: int, outcome: tuple[float, float]) -> Movement:
            return Movement(index=index, process=Movement.PROCESS_EXPLORATION,
                            status=Movement.STATUS_OK, action=np.zeros(24).tolist(),
                            outcome=list(outcome), goal=[0.0, 0.0], goal_index=1)

        real = movement(1, (0.2, -0.3))
        real.signature = list(record_key.movement_signature(key, real))
        deadline = time.monotonic() + 30
        while out.get_subscription_count() < 1 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
        out.publish(movement(10**15, (-0.05, -0.95)))  # forged: no signature
        out.publish(real)
        while node.app.learner.movement_count < 1 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
        for _ in range(10):  # anything else still on its way
            executor.spin_once(timeout_sec=0.05)
        status, state = _ask(node.server.port, "GET", "/api/state?landings=10")
        assert status == 200 and state["count"] == 1
        assert node.app.learner.movement_count == 1 and node.app.learner.indices == [1]
        assert node.app.picture.landings == 1
    finally:
        executor.shutdown()
        rogue.destroy_node()
        node.destroy_node()


def test_fuzzed_forged_movements_are_never_offered_nor_sent(rclpy_context, monkeypatch):
    """Property-based: any stream of movements, some signed by the run's simulator and the
    rest forged (unsigned, random signature bytes, a signed one changed, a huge index), goes
    through the page's own subscription; then offers at the forgeries' landings and their
    confirmation. The page counts only signed movements, and every offer and every
    demonstration it sends is a teaching-set entry or a movement the run signed."""
    import numpy as np
    from hypothesis import given
    from hypothesis import strategies as st
    from rclpy.parameter import Parameter

    from sgim_msgs.msg import Movement
    from sgim_ros import record_key
    from teacher.web_teacher_node import WebTeacherNode
    from tests.fuzz.tally import fuzz, tally

    key = record_key.new_key()
    monkeypatch.setenv(record_key.ENV, key)
    node = WebTeacherNode(context=rclpy_context, parameter_overrides=[
        Parameter("port", value=0), Parameter("render_casts", value=False)])
    (heard,) = [s.callback for s in node.subscriptions if s.topic_name == "/movements"]
    library = node.app.library
    genuine = {(np.asarray(a).tobytes(), np.asarray(y).tobytes())
               for a, y in zip(library.actions, library.outcomes, strict=True)}
    signed_count, keys = [0], [0]
    kinds = st.sampled_from(["signed", "unsigned", "random-signature", "changed", "far"])
    vectors = st.lists(st.floats(-1, 1), min_size=24, max_size=24)
    points = st.tuples(st.floats(-1, 1), st.floats(-1, 1))

    @fuzz(60)
    @given(steps=st.lists(st.tuples(kinds, vectors, points), min_size=1, max_size=8),
           signature=st.binary(max_size=20))
    def stream(steps, signature):
        forged_at = []
        for kind, action, outcome in steps:
            m = Movement(index=signed_count[0] + 1, process=Movement.PROCESS_EXPLORATION,
                         status=Movement.STATUS_OK, action=action, outcome=list(outcome),
                         goal=[0.0, 0.0], goal_index=1)
            if kind == "far":
                m.index = 10**15
            if kind in ("signed", "changed"):
                m.signature = list(record_key.movement_signature(key, m))
            elif kind == "random-signature":
                m.signature = list(signature)
            if kind == "changed":
                m.outcome = [outcome[0], outcome[1] + (0.25 if outcome[1] < 0 else -0.25)]
            heard(m)
            if kind == "signed":
                signed_count[0] += 1
                genuine.add((np.asarray(m.action, float).tobytes(),
                             np.asarray(m.outcome, float).tobytes()))
            else:
                forged_at.append(tuple(m.outcome))
            tally("web page: movements", kind)
        assert node.app.learner.movement_count == signed_count[0]
        for x, y in forged_at[:3]:
            offer = node.app.command({"command": "offer", "x": x, "y": y}, lambda d: d)
            assert offer["ok"], offer
            number = offer["offer"]["id"]
            decision = node.app.offers[number]
            pair = (np.asarray(decision.action, float).tobytes(),
                    np.asarray(decision.outcome, float).tobytes())
            assert pair in genuine, offer["message"]
            sent = []

            def send(decision, sent=sent):
                sent.append(decision)
                return {"ok": True, "message": "sent"}

            keys[0] += 1
            node.app.command({"command": "confirm", "offer": number,
                              "key": f"fuzz{keys[0]:08d}"}, send)
            assert len(sent) == 1 and sent[0] is decision
            tally("web page: offers at a forgery", "a signed movement or teaching entry")

    try:
        stream()
    finally:
        node.destroy_node()
