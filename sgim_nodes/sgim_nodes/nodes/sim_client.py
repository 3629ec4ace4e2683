"""Calls to the simulator's `execute_action` that survive a simulator restart, and give up.

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

A simulator that never answers is not waited for forever: after `service_retries` more tries
(each at most `service_timeout` to find the service, then `service_timeout` for its answer)
the call raises SimulatorUnavailable, which names the movement and the service, and the run
stops with it.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

from rclpy.node import Node
from rclpy.task import Future

from sgim_msgs.msg import Movement
from sgim_msgs.srv import ExecuteAction
from sgim_ros.entry import first_of
from sgim_ros.interfaces import calls
from sgim_ros.params import Param, at_least, positive

# The parameters of every node that calls the simulator; both may change while it runs.
SERVICE_TIMEOUT = Param("service_timeout", 30.0, "seconds to wait for the simulator's "
                        "service to be there, then as long for its answer, before trying the "
                        "same movement again", positive, read_only=False)
SERVICE_RETRIES = Param("service_retries", 3, "tries of one movement after the first that "
                        "got no answer; then the node gives up and the run stops, naming the "
                        "movement", at_least(0), read_only=False)
SIM_CLIENT_PARAMS = (SERVICE_TIMEOUT, SERVICE_RETRIES)
EXECUTE = calls("execute_action")  # the simulator's service, in the nodes' INTERFACES


class SimulatorError(RuntimeError):
    """The simulator refused the action (a bug upstream: actions are checked before)."""


class SimulatorUnavailable(SimulatorError):
    """No answer from the simulator after every try: the run cannot go on."""


class SimClient:
    """`settings` holds service_timeout and service_retries; it is read at every call, so a
    value changed while the node runs (the dict `declare` returns) applies at once."""

    def __init__(self, node: Node, settings: Mapping[str, Any]) -> None:
        self.node = node
        self.settings = settings
        self.client = EXECUTE.create(node)
        self.retries = 0  # over the node's life, for its log

    @property
    def timeout(self) -> float:
        return float(self.settings["service_timeout"])

    async def execute(self, request: ExecuteAction.Request) -> ExecuteAction.Response:
        tries = 0
        began = time.monotonic()
        while True:
            tries += 1
            if await self._service_ready(self.timeout):
                response = await self._call_with_timeout(request)
                if response is not None:
                    if response.status == Movement.STATUS_INVALID_ACTION:
                        raise SimulatorError(response.message)
                    return response
                # Sent but unanswered: a new call executes the movement again, and its record
                # says so, so that every node and reader takes that later record as the one
                # the learner used (bag/validation.py).
                request.attempt = min(request.attempt + 1, 255)
            if tries > self.settings["service_retries"]:
                raise SimulatorUnavailable(
                    f"no answer from execute_action for movement {request.movement_index} "
                    f"after {tries} tries in {time.monotonic() - began:.0f} s (service_timeout "
                    f"{self.timeout:g} s, service_retries {self.settings['service_retries']}):"
                    " is sim_bridge running?")
            self.retries += 1
            self.node.get_logger().warning(
                f"no answer from execute_action for movement {request.movement_index}; "
                f"waiting for the simulator and trying again ({tries}/"
                f"{self.settings['service_retries']} retries)")

    async def _service_ready(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while not self.client.service_is_ready():
            if time.monotonic() > deadline:
                return False
            await self._sleep(0.2)
        return True

    async def _call_with_timeout(self, request) -> ExecuteAction.Response | None:
        call = self.client.call_async(request)
        done = await first_of(self.node, call, self.timeout)
        if not done:
            self.client.remove_pending_request(call)
            return None
        return call.result()

    async def _sleep(self, seconds: float) -> None:
        await first_of(self.node, Future(), seconds)
