"""An rclpy node for tests: spin-until helpers, service calls and topic capture."""

from __future__ import annotations

import time
from collections.abc import Callable

DEFAULT_TIMEOUT = 30.0


class GraphClient:
    """Wraps one node and its executor so tests read as steps, not spin loops."""

    def __init__(self, context, name: str = "test_client") -> None:
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node

        self.node = Node(name, context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self._closed = False

    def spin_until(self, condition: Callable[[], bool], timeout: float = DEFAULT_TIMEOUT) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return True
            self.executor.spin_once(timeout_sec=0.05)
        return condition()

    def spin_for(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.05)

    def call(self, client, request, timeout: float = DEFAULT_TIMEOUT):
        answer = self.try_call(client, request, timeout)
        assert answer is not None, "service call timed out"
        return answer

    def ask(self, client, request, timeout: float = DEFAULT_TIMEOUT, attempt: float = 5.0):
        """`call` for a request that does the same when made twice (a query, a refused or
        repeated set): made again every `attempt` seconds, since its first reply may be lost
        (see `try_call`)."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            answer = self.try_call(client, request, min(attempt, max(left, 0.0)))
            if answer is not None:
                return answer
            assert time.monotonic() < deadline, "service call timed out"

    def try_call(self, client, request, timeout: float):
        """The answer, or None when none came in `timeout`. Right after discovery a reply can
        be lost: the server's reply writer may not have matched this client's reader yet
        (Fast DDS logs "failed to send response (timeout)"), though the request went through.
        Only for calls that may be made again."""
        future = client.call_async(request)
        if self.spin_until(future.done, timeout):
            return future.result()
        client.remove_pending_request(future)
        return None

    def capture(self, msg_type, topic: str, qos) -> list:
        received: list = []
        self.node.create_subscription(msg_type, topic, received.append, qos)
        return received

    def heard_by(self, topic: str, node_name: str) -> bool:
        """Whether the node named `node_name` subscribes to `topic` (not merely someone: a
        node another test left in the domain would do for get_subscription_count)."""
        return any(info.node_name == node_name
                   for info in self.node.get_subscriptions_info_by_topic(topic))

    def close(self) -> None:
        """Shut the executor down before destroying the node: its suspended wait generator
        holds a wait set and a timeout timer that point at the node's rcl entities, and
        shutdown is what drops it. Destroying the context's only node also tears its DDS
        participant down. Idempotent, so a test may close early and a fixture again."""
        if self._closed:
            return
        self._closed = True
        self.executor.shutdown()
        self.node.destroy_node()
