"""Per-goal cost of the region map, whole across two processes or folded where goals are drawn.

Grows a region tree to about the size a 5000-movement SGIM-D run reaches (225 regions), then
times each step a goal used to wait for (the interest computer's snapshot, message and
serialisation; the goal generator's deserialisation, check and snapshot from the message) and
what the goal generator does now (fold a competence into its LiveRegions, draw a goal, find
its region). Run inside the workspace environment:

    source ros_ws/env.sh && python benchmarks/bench_region_map.py
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from builtin_interfaces.msg import Time
from rclpy.serialization import deserialize_message, serialize_message

from sgim_msgs.msg import RegionMap
from sgim_nodes.bag.record_checks import Limits, check
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.goal_selection import GoalSelector
from sgim_nodes.core.learners import region_tree_for
from sgim_nodes.core.live_regions import LiveRegions
from sgim_nodes.core.region_snapshot import RegionIds, snapshot
from sgim_nodes.core.scale import unit_box
from sgim_nodes.nodes.ros_glue import region_map_msg, snapshot_from_msg


def per_call_ms(f, repeat: int = 200) -> float:
    start = time.perf_counter()
    for _ in range(repeat):
        f()
    return (time.perf_counter() - start) / repeat * 1e3


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--leaves", type=int, default=113, help="grow the tree to this many leaves")
    args = p.parse_args()
    c = LearnerConfig()
    tree = region_tree_for(c, unit_box(2, 0.07))
    rng = np.random.default_rng(0)
    goals = 0
    while len(tree.leaves) < args.leaves:  # goals crowded near the centre, competence skewed
        goal = rng.uniform(-1, 1, 2) ** 3
        tree.add(goal, -rng.uniform() * (1 + goal[0]) / 2)
        goals += 1
    snap = snapshot(tree, RegionIds(), goals)
    msg = region_map_msg(snap, 5000, Time())
    data = serialize_message(msg)
    modes = (c.p_mode1, c.p_mode2, c.p_mode3)
    print(f"{goals} goals, {len(snap.regions)} regions ({len(snap.leaves)} leaves), "
          f"map message {len(data)} bytes; ms per call:")
    ids = RegionIds()
    before = {
        "interest_computer: snapshot": lambda: snapshot(tree, ids, goals),
        "interest_computer: message": lambda: region_map_msg(snap, 5000, Time()),
        "interest_computer: serialise": lambda: serialize_message(msg),
        "goal_generator: deserialise": lambda: deserialize_message(data, RegionMap),
        "goal_generator: check": lambda: check("region_map", msg, Limits(24, 2)),
        "goal_generator: snapshot from the message": lambda: snapshot_from_msg(msg),
        "goal_generator: draw from the snapshot": lambda: GoalSelector(
            snap, modes, 0.05).sample(np.random.default_rng(1)),
    }
    live = LiveRegions(tree, goals)
    point = np.array([0.3, 0.2])
    after = {
        "draw from the bare tree (the runner)": lambda: GoalSelector(
            tree, modes, 0.05).sample(np.random.default_rng(1)),
        "LiveRegions: draw": lambda: GoalSelector(live, modes, 0.05).sample(
            np.random.default_rng(1)),
        "LiveRegions: region id": lambda: live.region_id(point),
        "LiveRegions: snapshot (interest_computer)": live.snapshot,
    }
    print("before, on the critical path of every goal:")
    for name, f in before.items():
        print(f"  {name:45s} {per_call_ms(f):6.2f}")
    print("now:")
    for name, f in after.items():
        print(f"  {name:45s} {per_call_ms(f):6.2f}")
    fold = per_call_ms(lambda: live.add(rng.uniform(-1, 1, 2) ** 3, -0.5), 50)
    print(f"  {'LiveRegions: fold one competence':45s} {fold:6.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
