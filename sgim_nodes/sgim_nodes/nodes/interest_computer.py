"""interest_computer: folds competence records into the region tree and publishes its map.

Competences come in order (keep-all QoS) and each is added to the core RegionTree, which
splits regions as they fill; after every record the whole map is published (latest-state
QoS), with the number of goals folded in, for the recorder, the markers and the plots. The
goal generator folds the same records into its own tree (core/live_regions.py names the
regions alike in both), so no goal waits for this map.

Interfaces:
  subscribes  competences (sgim_msgs/Competence)
  publishes   region_map  (sgim_msgs/RegionMap)
Parameters: the common ones and the region-tree ones of LearnerConfig (docs/reference.md).
"""

from __future__ import annotations

from typing import Any

from rclpy.node import Node

from sgim_msgs.msg import Competence
from sgim_nodes.bag.record_checks import Limits
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.learners import region_tree_for
from sgim_nodes.core.live_regions import LiveRegions
from sgim_nodes.nodes.ros_glue import (
    declare_learner,
    learner_node_params,
    region_map_msg,
    vec,
    world_scale,
)
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import declared, publishes, subscribes

PARAMS = learner_node_params()

REGION_MAP, COMPETENCES = publishes("region_map"), subscribes("competences")
INTERFACES = declared(REGION_MAP, COMPETENCES)


class InterestComputer(Node):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("interest_computer", **node_options)
        values, c = declare_learner(self, PARAMS)
        self.outcome_size = values["outcome_size"]
        tree, folded = region_tree_for(c, world_scale(values)), 0
        if values["resume_from"]:
            point = resume_point(values["resume_from"], c, values["resume_segments"])
            tree, folded = point.state.tree, point.state.n_competences
        self.regions = LiveRegions(tree, folded)
        self.gate = LiveGate(self.get_logger().error,
                             Limits(values["action_size"], self.outcome_size))
        self._map = REGION_MAP.create(self)
        COMPETENCES.create(self, self._on_competence)
        self._publish(0)

    def _on_competence(self, msg: Competence) -> None:
        if self.gate.check("competences", msg):  # the readers' checks: logged, not folded
            return
        self.regions.add(vec(msg.goal), float(msg.competence))
        self._publish(msg.movement_index)

    def _publish(self, movement_index: int) -> None:
        self._map.publish(region_map_msg(self.regions.snapshot(), movement_index,
                                         self.get_clock().now().to_msg()))


ENTRY = NodeEntry(InterestComputer)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
