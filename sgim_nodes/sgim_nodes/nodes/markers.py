"""markers: the run's live picture as MarkerArray topics, for rviz2 and Foxglove, and the bag.

It follows the run's topics into a LivePicture (view/picture.py, the web teacher's too) and
publishes, at most ``rate`` times a second and only what changed (view/markers.py):

  markers/landings        (RECORDS: every batch of new landings is kept; a full refresh every
                          ``full_every`` seconds, so a late viewer or a seeking replay
                          catches up)
  markers/regions, markers/teaching_goals, markers/current_goal   (LATEST_STATE: latched)

all in the frame ``outcome_space`` (set it as the fixed frame in rviz2; Foxglove picks it).
The recorder records them (bag.types.VIEW_TOPICS), so a replay shows the same picture.

Parameters: rate, full_every, tolerance_noise, outcome_noise, teaching_set.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from rclpy.node import Node
from visualization_msgs.msg import MarkerArray

from sgim_nodes.core.teaching import Teacher
from sgim_nodes.nodes.picture_feed import (
    PICTURE_INTERFACES,
    REACH_PARAMS,
    follow,
    reach_tolerance,
)
from sgim_nodes.view import markers
from sgim_nodes.view.picture import LivePicture
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import declared, publishes
from sgim_ros.params import Param, declare, positive
from sim_bridge.data_files import load_teaching_set
from sim_bridge.data_params import TEACHING_SET_FILE

PARAMS = (
    Param("rate", 2.0, "publications per second at most (the picture changes faster)",
          lambda v: 0 < v <= 50, "in (0, 50]"),
    Param("full_every", 5.0, "seconds between full landings refreshes (between them only new "
          "landings are sent)", positive, "> 0"),
    *REACH_PARAMS,
    Param("teaching_set", "", "teaching-set file (.npz); empty: the packaged one",
          TEACHING_SET_FILE),
)

# The picture's layers (docs/markers.md), each its own topic.
LAYERS = tuple(publishes(f"markers/{layer}")
               for layer in ("landings", "regions", "teaching_goals", "current_goal"))
INTERFACES = declared(*LAYERS, PICTURE_INTERFACES)


class MarkersNode(Node):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("markers", **node_options)
        p = declare(self, PARAMS)
        ts = load_teaching_set(p["teaching_set"] or None)
        teacher = Teacher(ts.actions, ts.outcomes, np.random.default_rng(0),
                          tolerance=reach_tolerance(p))
        self.picture = LivePicture(teacher)
        follow(self, self.picture)
        self.full_every = p["full_every"]
        self._landings, self._regions, self._teaching, self._goal = (
            layer.create(self) for layer in LAYERS)
        self._sent = {"landings": 0, "regions": -1, "teaching": -1, "goal": -1}
        self._batch = 0
        self._last_full = -float("inf")
        self.create_timer(1.0 / p["rate"], self._publish)
        self._publish()  # the teaching goals and an empty picture before the run starts
        self.get_logger().info(f"{len(ts.outcomes)} teaching goals; publishing markers at "
                               f"{p['rate']:g} Hz in frame '{markers.FRAME}'")

    def _publish(self) -> None:
        pic, sent = self.picture, self._sent
        stamp = self.get_clock().now().to_msg()
        now = self.get_clock().now().nanoseconds * 1e-9
        if now - self._last_full >= self.full_every and pic.landings != self._full_size():
            self._last_full, self._batch = now, 0
            self._landings.publish(markers.landings_full(pic, stamp))
            sent["landings"] = pic.landings
        elif pic.landings > sent["landings"]:
            self._batch += 1
            self._landings.publish(MarkerArray(markers=[
                markers.landings(pic, sent["landings"], self._batch, stamp)]))
            sent["landings"] = pic.landings
        pic.judge_teaching_goals()
        for key, version, publisher, build in (
                ("regions", pic.regions_version, self._regions, markers.regions),
                ("teaching", pic.teaching_version, self._teaching, markers.teaching_goals),
                ("goal", pic.goal_version, self._goal, markers.current_goal)):
            if version != sent[key]:
                sent[key] = version
                publisher.publish(build(pic, stamp))

    def _full_size(self) -> int:
        """Landings in the last full refresh (-1 before any), to skip identical refreshes."""
        return self._sent["landings"] if self._batch == 0 and self._last_full > -1 else -1


ENTRY = NodeEntry(MarkersNode)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
