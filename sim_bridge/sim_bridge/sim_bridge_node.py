"""ROS 2 node that executes actions in the fishing world: the ExecuteAction service.

Thin by design: validation and physics live in fishing_world; this node translates the
request, stamps the result and publishes every executed movement on `movements` for the
recorder. Movement k is cast with the k-th noise of the seed's stream, also after a restart
(noise_cursor.py). Bad input is answered with STATUS_INVALID_ACTION and a message, never a
crash, and is not published (nothing was executed).

Interfaces:
  service  execute_action (sgim_msgs/srv/ExecuteAction)
  topic    movements      (sgim_msgs/msg/Movement, RECORDS QoS: reliable, keep all)
Parameters: seed, noise, time_step (see PARAMS).
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
from rclpy.node import Node

from sgim_msgs.msg import Movement
from sgim_msgs.srv import ExecuteAction
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import declared, publishes, serves
from sgim_ros.params import Bounds, Param, declare, non_negative, seed_range
from sgim_ros.record_key import REEXECUTION_LOG, from_environment, movement_signature
from sim_bridge.fishing_world import DEFAULT_NOISE, DEFAULT_TIME_STEP, FishingWorld
from sim_bridge.noise_cursor import NoiseCursor

PARAMS = (  # all read-only: they are the run's physics, recorded in its metadata
    Param("seed", 0, "seed of the motor-command noise; same seed, same outcomes", seed_range),
    Param("noise", DEFAULT_NOISE, "std of the noise added to the motor commands",
          non_negative),
    Param("time_step", DEFAULT_TIME_STEP, "physics time step in seconds",
          Bounds(0.0, 0.01, low_open=True)),
    Param("wait_for_recorder", False, "serve execute_action only once the recorder hears the "
          "movements (a node restarted mid-run would otherwise lose its first records)"),
    Param("movement_listeners", "recorder", "with wait_for_recorder: the nodes (comma-"
          "separated names) that must hear the movements before execute_action is served; the "
          "launcher names every node of the run's graph that listens to them",
          lambda v: all(name.strip() for name in v.split(",")), "comma-separated node names"),
)

MOVEMENTS, EXECUTE = publishes("movements"), serves("execute_action")
INTERFACES = declared(MOVEMENTS, EXECUTE)


class SimBridgeNode(Node):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("sim_bridge", **node_options)
        p = declare(self, PARAMS)
        self.world = FishingWorld(seed=p["seed"], noise=p["noise"], time_step=p["time_step"])
        # Movement k gets the k-th noise of the seed's stream, even after a restart, a resume
        # or a re-execution: the same seed's uninterrupted run's noise (noise_cursor.py).
        self.cursor = NoiseCursor(self.world)
        self.executed = 0
        self._key = from_environment()  # the run's record key (sgim_ros/record_key.py)
        self._movements = MOVEMENTS.create(self)
        self._service = None
        self._listeners = {name.strip() for name in p["movement_listeners"].split(",")}
        if p["wait_for_recorder"]:
            self._gate = self.create_timer(0.1, self._open_when_recorded)
        else:
            self._open()
        self.get_logger().info(
            f"fishing world ready (seed {p['seed']}, noise {p['noise']}, "
            f"dt {p['time_step']:.5f} s, action size {self.world.action_dim})"
        )

    def _open(self) -> None:
        self._service = EXECUTE.create(self, self._execute)

    def _open_when_recorded(self) -> None:
        """Clients wait for the service, so holding it back holds every movement back until
        every expected listener (`movement_listeners`) is discovered and every discovered
        listener is matched. A simulator restarted mid-run needs this most: its publisher is
        new to all of them, and a listener that missed a movement could not go on."""
        listeners = self.get_subscriptions_info_by_topic(self._movements.topic_name)
        if (self._listeners <= {info.node_name for info in listeners}
                and self._movements.get_subscription_count() >= len(listeners)):
            self._gate.cancel()
            self._open()
            self.get_logger().info(f"{', '.join(sorted(self._listeners))} hear the movements: "
                                   "serving execute_action")

    def _execute(self, request: ExecuteAction.Request, response: ExecuteAction.Response):
        result = self.cursor.execute(np.asarray(request.action, dtype=float),
                                     request.movement_index if request.record else None)
        response.status = int(result.status)
        response.message = result.message
        if result.outcome is not None:
            response.outcome = [float(v) for v in result.outcome]
        if result.status == Movement.STATUS_INVALID_ACTION:
            self.get_logger().warning(f"refused an action: {result.message}")
            return response
        self.executed += 1
        if request.record:
            movement = Movement(
                stamp=self.get_clock().now().to_msg(),
                index=request.movement_index,
                process=request.process,
                status=response.status,
                action=list(request.action),
                outcome=response.outcome,
                goal=list(request.goal),
                goal_index=request.goal_index,
                attempt=request.attempt,
            )
            if self._key:  # the run's proof that this simulator made the record
                movement.signature = list(movement_signature(self._key, movement))
            if request.attempt:  # the readers confirm a re-execution from this line
                self.get_logger().warning(REEXECUTION_LOG.format(
                    index=request.movement_index, attempt=request.attempt)
                    + ": its client got no answer the first time")
            self._movements.publish(movement)
        return response

    def destroy_node(self) -> None:
        self.world.close()
        super().destroy_node()


ENTRY = NodeEntry(SimBridgeNode)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    sys.exit(main())
