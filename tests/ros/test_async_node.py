"""AsyncNode (sgim_ros/entry.py): its publishers and subscriptions carry no default QoS-event
handler, which its executor would walk at every wake-up, and messages still flow."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.ros


def event_handlers(node) -> int:
    from rclpy.event_handler import EventHandler

    return sum(isinstance(w, EventHandler) for w in node.waitables)


def test_an_async_node_leaves_out_the_default_qos_event_handlers(rclpy_context):
    from rclpy.event_handler import SubscriptionEventCallbacks
    from rclpy.node import Node
    from std_msgs.msg import String

    from sgim_ros.entry import AsyncNode

    plain = Node("plain", context=rclpy_context)
    lean = AsyncNode("lean", context=rclpy_context)
    try:
        for node in (plain, lean):
            node.create_publisher(String, "chatter", 10)
            node.create_subscription(String, "chatter", lambda _: None, 10)
        assert event_handlers(plain) >= 2, "rclpy's default handlers: the baseline"
        assert event_handlers(lean) == 0
        # A handler the node asks for is kept.
        lean.create_subscription(String, "other", lambda _: None, 10,
                                 event_callbacks=SubscriptionEventCallbacks(
                                     incompatible_qos=lambda _: None))
        assert event_handlers(lean) >= 1
    finally:
        plain.destroy_node()
        lean.destroy_node()


def test_an_async_node_still_receives_what_it_publishes(rclpy_context):
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import String

    from sgim_ros.entry import AsyncNode

    node = AsyncNode("echo", context=rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    received: list[str] = []
    try:
        publisher = node.create_publisher(String, "echo", 10)
        node.create_subscription(String, "echo", lambda m: received.append(m.data), 10)
        for _ in range(200):
            publisher.publish(String(data="hello"))
            executor.spin_once(timeout_sec=0.05)
            if received:
                break
        assert received and received[0] == "hello"
    finally:
        executor.shutdown()
        node.destroy_node()
