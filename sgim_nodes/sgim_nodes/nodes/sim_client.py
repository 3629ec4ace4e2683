"""Calls to the simulator's `execute_action` that survive a simulator restart.

A learning run must not lose or double a movement when the simulator node dies: if no answer
comes within the timeout, the client waits for the service to come back and sends the same
request again with `attempt` + 1. The record of that re-execution carries its attempt number:
it supersedes an earlier record of the same index for every node and every bag reader
(bag/validation.py), never "the last record wins".

Why always execute again, even when a record of the first execution came in: a dying
simulator's last record may have reached some subscribers and not others (the recorder and
the explorer, say, but not the evaluator). Only a new record, published by a live simulator
to every subscriber, gives every node the same movement; without it a node that missed the
first record would wait for that index forever (or, leniently, learn without it).
"""

from __future__ import annotations

from rclpy.node import Node
from rclpy.task import Future

from sgim_msgs.msg import Movement
from sgim_msgs.srv import ExecuteAction
from sgim_ros.entry import first_of
from sgim_ros.params import Param, positive

# The parameter of every node that calls the simulator.
SERVICE_TIMEOUT = Param("service_timeout", 30.0, "seconds to wait for the simulator's answer "
                        "before retrying the same movement", positive, "> 0")


class SimulatorError(RuntimeError):
    """The simulator refused the action (a bug upstream: actions are checked before)."""


class SimClient:
    def __init__(self, node: Node, timeout: float) -> None:
        self.node = node
        self.timeout = timeout
        self.client = node.create_client(ExecuteAction, "execute_action")
        self.retries = 0

    async def execute(self, request: ExecuteAction.Request) -> ExecuteAction.Response:
        while True:
            if self.client.service_is_ready():
                response = await self._call_with_timeout(request)
                if response is not None:
                    if response.status == Movement.STATUS_INVALID_ACTION:
                        raise SimulatorError(response.message)
                    return response
                # Sent but unanswered: a new call executes the movement again, and its record
                # says so, so that every node and reader takes that later record as the one
                # the learner used (bag/validation.py).
                request.attempt = min(request.attempt + 1, 255)
            else:
                await self._sleep(0.2)
            self.retries += 1
            self.node.get_logger().warning(
                f"no answer from execute_action for movement {request.movement_index}; "
                f"waiting for the simulator and retrying (retry {self.retries})")

    async def _call_with_timeout(self, request) -> ExecuteAction.Response | None:
        call = self.client.call_async(request)
        done = await first_of(self.node, call, self.timeout)
        if not done:
            self.client.remove_pending_request(call)
            return None
        return call.result()

    async def _sleep(self, seconds: float) -> None:
        await first_of(self.node, Future(), seconds)
