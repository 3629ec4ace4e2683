"""goal_generator: self-generated goals by the three SAGG-RIAC modes, from the region map.

The arbiter asks for each goal through `choose_goal`, saying how many attempted goals the map
must already reflect; the answer waits for that map, so the choice never depends on message
timing, and the random stream "goals" makes it the very goal the single-process learner draws.

Interfaces:
  subscribes  region_map  (sgim_msgs/RegionMap)
  publishes   goals       (sgim_msgs/Goal)
  serves      choose_goal (sgim_msgs/srv/ChooseGoal)
Parameters: the common ones, p_mode1..3 and mode3_radius_noise of LearnerConfig, map_timeout.
The random-goals learner draws every goal uniformly (mode 2). A request that names a
`demonstrated` outcome (a goal-only demonstration, issue 14) adopts it as the goal
(MODE_DEMONSTRATION), drawing nothing, as the single-process learner adopts it.
"""

from __future__ import annotations

import numpy as np
from rclpy.task import Future

from sgim_msgs.msg import Goal, RegionMap
from sgim_msgs.srv import ChooseGoal
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.bag.validation import Limits, LiveGate
from sgim_nodes.core.goal_selection import GoalSelector
from sgim_nodes.core.learners import goal_mode_probabilities
from sgim_nodes.core.random_streams import component_rng
from sgim_nodes.core.region_snapshot import RegionSnapshot
from sgim_nodes.nodes.ros_glue import (
    AsyncNode,
    check_vector,
    declare_learner,
    floats,
    learner_node_params,
    run_node,
    snapshot_from_msg,
    vec,
    world_scale,
)
from sgim_ros import qos
from sgim_ros.entry import first_of
from sgim_ros.params import Param, positive

MODE_CODES = {1: Goal.MODE_INTEREST_REGION, 2: Goal.MODE_UNIFORM, 3: Goal.MODE_LEAST_COMPETENT}
PARAMS = learner_node_params(
    Param("map_timeout", 60.0, "seconds to wait for a region map that reflects the requested "
          "number of goals", positive),
)


class GoalGenerator(AsyncNode):
    def __init__(self) -> None:
        super().__init__("goal_generator")
        values, c = declare_learner(self, PARAMS)
        self.timeout = values["map_timeout"]
        self.outcome_size = values["outcome_size"]
        self.rng = component_rng(values["seed"], "goals")
        self.probabilities = goal_mode_probabilities(c, values["learner"])
        self.radius = c.distances(world_scale(values)).mode3_radius
        self.snapshot: RegionSnapshot | None = None
        self.goal_count = 0
        if values["resume_from"]:
            self.goal_count = resume_point(values["resume_from"], c,
                                 values["resume_segments"]).goal_index
        self._waiters: list[tuple[int, Future]] = []
        self.gate = LiveGate(self.get_logger().error,
                             Limits(values["action_size"], values["outcome_size"]))
        self._goals = self.create_publisher(Goal, "goals", qos.RECORDS)
        self.create_subscription(RegionMap, "region_map", self._on_map, qos.LATEST_STATE)
        self.create_service(ChooseGoal, "choose_goal", self._choose)

    def _on_map(self, msg: RegionMap) -> None:
        if self.gate.check("region_map", msg):  # the readers' checks: logged, not used
            return
        if self.snapshot is not None and msg.goal_count < self.snapshot.goal_count:
            return  # an older map arriving late never replaces a newer one
        self.snapshot = snapshot_from_msg(msg)
        for needed, future in list(self._waiters):
            if self.snapshot.goal_count >= needed and not future.done():
                future.set_result(True)
        self._waiters = [(n, f) for n, f in self._waiters if not f.done()]

    async def _choose(self, request: ChooseGoal.Request, response: ChooseGoal.Response):
        if self.snapshot is None or self.snapshot.goal_count < request.min_goal_count:
            ready = Future(executor=self.executor)
            self._waiters.append((request.min_goal_count, ready))
            if not await first_of(self, ready, self.timeout):
                self._waiters = [(n, f) for n, f in self._waiters if f is not ready]
                have = -1 if self.snapshot is None else self.snapshot.goal_count
                response.ok = False
                response.message = (f"no region map with {request.min_goal_count} goals after "
                                    f"{self.timeout} s (latest has {have}): is interest_computer "
                                    "running?")
                return response
        snap = self.snapshot
        if len(request.demonstrated):
            why = check_vector(request.demonstrated, self.outcome_size, "demonstrated goal",
                               bound=1.0)
            if why:
                response.ok, response.message = False, why
                return response
            point, mode = vec(request.demonstrated), Goal.MODE_DEMONSTRATION
        else:
            choice = GoalSelector(snap, self.probabilities, self.radius).sample(self.rng)
            point, mode = choice.goal, MODE_CODES[choice.mode]
        self.goal_count += 1
        leaf = next((r for r in snap.leaves if np.all(point >= r.low)
                     and np.all(point <= r.high)), None)
        goal = Goal(stamp=self.get_clock().now().to_msg(), index=self.goal_count,
                    movement_index=request.movement_index, point=floats(point),
                    region_id=-1 if leaf is None else leaf.id, mode=mode)
        self._goals.publish(goal)
        response.ok, response.goal = True, goal
        return response


def main(args: list[str] | None = None) -> int:
    return run_node(GoalGenerator, args)


if __name__ == "__main__":
    raise SystemExit(main())
