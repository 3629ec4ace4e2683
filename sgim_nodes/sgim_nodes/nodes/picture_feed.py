"""Feed a LivePicture from the graph's topics: the one subscription list of every viewer.

The web teacher and the markers node both follow a run through the same topics into the same
picture (view/picture.py). ``lock``: held while a message changes the picture, for a viewer
that reads it from another thread (the web server's).
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable
from typing import Any

from rclpy.node import Node

from sgim_msgs.msg import (
    Demonstration,
    Evaluation,
    Goal,
    Movement,
    RegionMap,
    RunStatus,
)
from sgim_nodes.bag.record_checks import Limits
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.teaching import DEFAULT_TOLERANCE_NOISE, MEANS_AND_GOAL
from sgim_nodes.view.picture import DemonstrationSeen, Leaf, LivePicture
from sgim_ros.interfaces import subscribes
from sgim_ros.params import Param, non_negative, positive
from sim_bridge.scaling import OUTCOME_NOISE

# "Reached" as the automatic teacher judges it (teacher_node.py): within tolerance_noise x
# outcome_noise of a landing. Every viewer and human teacher takes the same two parameters,
# which a run's parameter file gives every node, so they all agree with the automatic teacher.
REACH_PARAMS = (
    Param("tolerance_noise", DEFAULT_TOLERANCE_NOISE, "a teaching goal counts as reached "
          "within this many units of the world's outcome noise (the automatic teacher's)",
          non_negative, ">= 0"),
    Param("outcome_noise", OUTCOME_NOISE, "the world's outcome noise (outcome units)",
          positive, "> 0"),
)


def reach_tolerance(values: dict) -> float:
    """The distance under which a teaching goal counts as reached, from REACH_PARAMS."""
    return float(values["tolerance_noise"] * values["outcome_noise"])

# What the picture shows, in the INTERFACES of each node that follows it.
PICTURE_TOPICS = ("movements", "region_map", "goals", "evaluations", "demonstrations",
                  "run_status")
PICTURE_INTERFACES = tuple(subscribes(topic) for topic in PICTURE_TOPICS)
RUN_STATES = {RunStatus.STATE_RUNNING: "running", RunStatus.STATE_FINISHED: "finished",
              RunStatus.STATE_ABORTED: "aborted"}


def follow(node: Node, picture: LivePicture, lock: threading.Lock | None = None,
           also: Callable[[Movement], None] | None = None) -> dict[str, Any]:
    """Subscribe ``node`` to every topic the picture shows; return the subscriptions by topic.
    A movement is shown only once the run's checks admit it (signature, size, its place in
    the count: bag/validation.py's LiveGate, refusals logged), then handed to ``also``."""
    guard = lock if lock is not None else contextlib.nullcontext()
    gate = LiveGate(node.get_logger().warning, Limits())
    gate.movements.resync()  # the first valid movement sets the count (a resumed run)

    def on_movement(msg: Movement) -> None:
        if msg.process == Movement.PROCESS_EVALUATION or not gate.admit_movement(msg).ok:
            return
        if also is not None:
            also(msg)
        with guard:
            picture.add_movement(msg.index, msg.process, msg.status == Movement.STATUS_OK,
                                 msg.outcome, msg.goal)

    def on_regions(msg: RegionMap) -> None:
        leaves = [Leaf((r.lower[0], r.lower[1]), (r.upper[0], r.upper[1]), float(r.interest))
                  for r in msg.regions if r.is_leaf and len(r.lower) == 2 == len(r.upper)]
        with guard:
            picture.set_regions(leaves)

    def on_goal(msg: Goal) -> None:
        if len(msg.point) == 2:
            with guard:
                picture.set_goal(msg.point)

    def on_evaluation(msg: Evaluation) -> None:
        with guard:
            picture.add_evaluation(msg.movement_index, msg.mean_distance)

    def on_demonstration(msg: Demonstration) -> None:
        if gate.check("demonstrations", msg):  # forged or malformed: not shown
            return
        with guard:
            picture.add_demonstration(DemonstrationSeen(
                int(msg.index), int(msg.movement_index), tuple(float(v) for v in msg.outcome),
                int(msg.teaching_set_index), str(msg.source),
                content=str(msg.content) or MEANS_AND_GOAL))

    def on_status(msg: RunStatus) -> None:
        with guard:
            picture.set_status(msg.learner, msg.movement_index, msg.total_movements,
                               RUN_STATES.get(msg.state, "running"), msg.message)

    callbacks = (on_movement, on_regions, on_goal, on_evaluation, on_demonstration, on_status)
    return {endpoint.name: endpoint.create(node, callback)
            for endpoint, callback in zip(PICTURE_INTERFACES, callbacks, strict=True)}
