"""goal_generator: self-generated goals by the three SAGG-RIAC modes, from its region tree.

It folds every competence into its own region tree, as the interest computer does into the one
whose map it publishes: a goal waits for one small record from the explorer, not for a whole
map rebuilt, sent and checked by a second process (the map grows with the run; docs/guide.md,
"How a run flows"). The explorer asks for each goal through `choose_goal` (within its
reach_goal job), saying how many attempted goals the tree must already hold; the answer waits
for them, so the choice never depends on message timing, and the random stream "goals" makes it
the very goal the single-process learner draws. Region ids are named in the map's order
(core/live_regions.py), so a Goal's region_id is that of the interest computer's map.

Interfaces:
  subscribes  competences (sgim_msgs/Competence)
  publishes   goals       (sgim_msgs/Goal)
  serves      choose_goal (sgim_msgs/srv/ChooseGoal), goal_generator_ready (RecorderReady)
Parameters: the common ones, the region-tree ones and p_mode1..3, mode3_radius_noise of
LearnerConfig, map_timeout. The random-goals learner draws every goal uniformly (mode 2). A
request that names a `demonstrated` outcome (a goal-only demonstration, issue 14) adopts it as
the goal (MODE_DEMONSTRATION), drawing nothing, as the single-process learner adopts it.

SGIM-ACTS (issue 33) draws a (strategy, goal) pair instead (core/strategy_choice.py, random
stream "strategies"), over autonomous and the mimicry and emulation of each of `teachers`: its
Goal names the strategy, and each Competence, which names it too, goes into that strategy's
history of its region (core/strategy_regions.py).
"""

from __future__ import annotations

from typing import Any

from rclpy.task import Future

from sgim_msgs.msg import Competence, Goal
from sgim_msgs.srv import ChooseGoal
from sgim_nodes.bag.record_checks import Limits
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.goal_selection import GoalSelector
from sgim_nodes.core.learner_registry import goal_mode_probabilities
from sgim_nodes.core.learners import region_tree_for
from sgim_nodes.core.live_regions import LiveRegions
from sgim_nodes.core.random_streams import component_rng
from sgim_nodes.nodes.ros_glue import (
    ACTS,
    TEACHERS,
    AsyncNode,
    check_vector,
    declare_learner,
    floats,
    learner_node_params,
    teacher_names,
    vec,
    world_scale,
)
from sgim_ros.entry import first_of
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import declared, publishes, serves, subscribes
from sgim_ros.params import Param, ParameterError, positive
from sgim_ros.ready import serve_ready

MODE_CODES = {1: Goal.MODE_INTEREST_REGION, 2: Goal.MODE_UNIFORM, 3: Goal.MODE_LEAST_COMPETENT}
PARAMS = learner_node_params(
    Param("map_timeout", 60.0, "seconds to wait until the region tree holds the requested "
          "number of attempted goals", positive),
    TEACHERS,
)


def acts_choice(config, scale, teachers: str):
    """SGIM-ACTS's (strategy, region) histories and its chooser, over ``teachers``."""
    from sgim_nodes.core.strategies import all_strategies
    from sgim_nodes.core.strategy_choice import StrategyChooser
    from sgim_nodes.core.strategy_regions import StrategyRegions

    try:
        strategies = all_strategies(teacher_names(teachers), config)
    except ValueError as error:
        raise ParameterError(f"parameter 'teachers': {error}") from error
    regions = StrategyRegions(region_tree_for(config, scale), [s.name for s in strategies])
    return regions, StrategyChooser(regions, strategies,
                                    (config.p_mode1, config.p_mode2, config.p_mode3),
                                    config.distances(scale).mode3_radius,
                                    config.strategy_choice_order, config.strategy_value)

GOALS, COMPETENCES = publishes("goals"), subscribes("competences")
READY, CHOOSE = serves("goal_generator_ready"), serves("choose_goal")
INTERFACES = declared(GOALS, COMPETENCES, READY, CHOOSE)


class GoalGenerator(AsyncNode):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("goal_generator", **node_options)
        values, c = declare_learner(self, PARAMS)
        self.timeout = values["map_timeout"]
        self.outcome_size = values["outcome_size"]
        self.acts = values["learner"] == ACTS
        self.rng = component_rng(values["seed"], "strategies" if self.acts else "goals")
        self.goal_count = 0
        tree, folded = region_tree_for(c, world_scale(values)), 0
        if self.acts:
            self.strategy_regions, self.chooser = acts_choice(c, world_scale(values),
                                                              values["teachers"])
        if values["resume_from"]:
            point = resume_point(values["resume_from"], c, values["resume_segments"])
            self.goal_count = point.goal_index
            tree, folded = point.state.tree, point.state.n_competences
            if self.acts:  # each competence into its strategy's history, as the tree folds it
                for comp in sorted(point.records.competences, key=lambda r: r.movement_index):
                    try:
                        self.strategy_regions.add(comp.strategy, comp.goal, comp.competence)
                    except ValueError as error:
                        raise ParameterError(f"resume: the recorded competence of goal "
                                             f"{comp.goal_index}: {error}") from error
        self.regions = LiveRegions(tree, folded)
        self.selector = GoalSelector(self.regions, goal_mode_probabilities(c, values["learner"]),
                                     c.distances(world_scale(values)).mode3_radius)
        self._waiters: list[tuple[int, Future]] = []
        self.gate = LiveGate(self.get_logger().error,
                             Limits(values["action_size"], values["outcome_size"]))
        self._goals = GOALS.create(self)
        competences = COMPETENCES.create(self, self._on_competence)
        # A competence missed before the DDS match would stall every later goal.
        serve_ready(self, READY, {"competences": competences})
        CHOOSE.create(self, self._choose)

    def _on_competence(self, msg: Competence) -> None:
        if self.gate.check("competences", msg):  # the readers' checks: logged, not folded
            return
        self.regions.add(vec(msg.goal), float(msg.competence))
        if self.acts:
            try:
                self.strategy_regions.add(msg.strategy, vec(msg.goal), float(msg.competence))
            except ValueError as error:  # a strategy this learner does not have
                self.get_logger().error(f"competence of goal {msg.goal_index}: {error}")
        for needed, future in self._waiters:
            if self.regions.goal_count >= needed and not future.done():
                future.set_result(True)
        self._waiters = [(n, f) for n, f in self._waiters if not f.done()]

    async def _choose(self, request: ChooseGoal.Request, response: ChooseGoal.Response):
        if self.regions.goal_count < request.min_goal_count:
            ready = Future(executor=self.executor)
            self._waiters.append((request.min_goal_count, ready))
            if not await first_of(self, ready, self.timeout):
                self._waiters = [(n, f) for n, f in self._waiters if f is not ready]
                response.ok = False
                response.message = (f"no competence of attempted goal {request.min_goal_count} "
                                    f"after {self.timeout} s (the tree holds "
                                    f"{self.regions.goal_count}): is low_level_explorer "
                                    "running?")
                return response
        if len(request.demonstrated):
            why = check_vector(request.demonstrated, self.outcome_size, "demonstrated goal",
                               bound=1.0)
            if why:
                response.ok, response.message = False, why
                return response
            point, mode = vec(request.demonstrated), Goal.MODE_DEMONSTRATION
            strategy = ""
        elif self.acts:
            pair = self.chooser.sample(self.rng)
            point, mode, strategy = pair.goal, MODE_CODES[pair.mode], pair.strategy.name
        else:
            choice = self.selector.sample(self.rng)
            point, mode, strategy = choice.goal, MODE_CODES[choice.mode], ""
        self.goal_count += 1
        goal = Goal(stamp=self.get_clock().now().to_msg(), index=self.goal_count,
                    movement_index=request.movement_index, point=floats(point),
                    region_id=self.regions.region_id(point), mode=mode, strategy=strategy)
        self._goals.publish(goal)
        response.ok, response.goal = True, goal
        return response


ENTRY = NodeEntry(GoalGenerator)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
