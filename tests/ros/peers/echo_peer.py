"""The other process of the interface round-trip test.

It echoes every sgim_msgs message from /roundtrip/in/<Name> to /roundtrip/out/<Name>, serves
ExecuteAction with a fake world (outcome = mean of each half of the action) and an Imitate
action that reports feedback. It prints READY once everything is advertised.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import rclpy
from rclpy.action import ActionServer
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
from tests.ros.interface_samples import message_class, message_names

QOS = QoSProfile(depth=10, history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)


class EchoPeer(Node):
    def __init__(self) -> None:
        super().__init__("echo_peer")
        from sgim_msgs.action import Imitate
        from sgim_msgs.srv import ExecuteAction

        self._keep = []
        for name in message_names():
            cls = message_class(name)
            pub = self.create_publisher(cls, f"/roundtrip/out/{name}", QOS)
            self._keep.append(
                self.create_subscription(cls, f"/roundtrip/in/{name}", pub.publish, QOS)
            )
        self.create_service(ExecuteAction, "/roundtrip/execute_action", self._execute)
        self._action = ActionServer(self, Imitate, "/roundtrip/imitate", self._imitate)

    def _execute(self, request, response):
        from sgim_msgs.msg import Movement

        action = list(request.action)
        if len(action) != 24:
            response.status = Movement.STATUS_INVALID_ACTION
            response.message = f"action has {len(action)} numbers, expected 24"
            return response
        response.status = Movement.STATUS_OK
        response.outcome = [sum(action[:12]) / 12, sum(action[12:]) / 12]
        return response

    def _imitate(self, goal_handle):
        from sgim_msgs.action import Imitate

        request = goal_handle.request
        for k in range(request.repetitions):
            goal_handle.publish_feedback(Imitate.Feedback(movements_done=k + 1))
            time.sleep(0.05)
        goal_handle.succeed()
        return Imitate.Result(
            movements_used=request.repetitions,
            best_outcome=list(request.outcome),
            best_distance=0.25,
            cancelled=False,
        )


def main() -> None:
    rclpy.init()
    node = EchoPeer()
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    print("READY", flush=True)
    try:
        executor.spin()
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
