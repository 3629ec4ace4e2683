"""A node that serves services and never answers them: a hung simulator or recorder.

    python tests/ros/peers/silent_peer.py NAME SERVICE... [anything else, ignored]

NAME is its node name; each SERVICE is `execute_action` or `recorder_ready` (relative names).
Requests are taken and left unanswered forever. Extra arguments are ignored, so that it can
stand in for a node through run_experiment's --prefix (which appends the node's command).
"""

from __future__ import annotations

import contextlib
import sys

import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.task import Future

SERVICES = ("execute_action", "recorder_ready")


def main() -> int:
    name, services = sys.argv[1], [a for a in sys.argv[2:] if a in SERVICES]
    rclpy.init(args=["--ros-args"])
    node = Node(name)
    from sgim_msgs.srv import ExecuteAction, RecorderReady

    types = {"execute_action": ExecuteAction, "recorder_ready": RecorderReady}
    group = ReentrantCallbackGroup()

    async def never(request, response):
        await Future()  # taken, never answered
        return response

    for service in services:
        node.create_service(types[service], service, never, callback_group=group)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    print(f"silent {name}: {', '.join(services)}", flush=True)
    with contextlib.suppress(KeyboardInterrupt, ExternalShutdownException):
        executor.spin()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
