"""low_level_explorer: reaches goals, one after the other (inverse model, Nelder-Mead, exploration).

A `reach_goal` job spans the goals between two of the arbiter's boundaries (a teacher's turn,
the budget, a human's pause or step): for each goal the explorer asks the goal generator
(`choose_goal`, saying how many attempted goals its region tree must hold, so the choice never
depends on message timing), then drives one core GoalAttempt movement by movement. Its actions
are executed through the simulator's `execute_action` service, and the job waits until each
movement has come back on the `movements` stream into its memory before the next step, as the
single-process learner would. Each attempt's competence is published on `competences` as soon
as it spent a movement (marked from_demonstration for a demonstrated outcome adopted as a
goal: a goal-only demonstration, which the arbiter sends as a job of that one goal). Why the
explorer, not the arbiter, asks for the next goal: three processes crossed in series at every
goal (a ROS action's result, a service call, a new action) cost about 7 ms per goal, with 1.5
movements per goal (docs/guide.md, "How a run flows").

The job ends at its movement cap (the goal under way is cut there), after `max_goals` goals, or
at a cancel (the arbiter preempting for a demonstration or a pause), honoured at the next
movement boundary: the movement under way always completes, and no goal is chosen after the
cancel. The result counts the job's movements and attempted goals, and describes its last goal
(whether it ended by itself or was cut).

SGIM-ACTS (issue 33): each Goal names a strategy. An autonomous one is attempted as above; a
social one ends the job before any movement, handing the goal and the memory's distance to it
back to the arbiter (`social`), which asks the teacher. An emulation comes back as a job of
one goal: the teacher's outcome to reach (`demonstrated`) and the chosen goal (`chosen`).
Every SGIM-ACTS episode's competence is measured at the goal the learner chose, against the
memory's distance to it when chosen (core/competence.NearestOutcome), and names the strategy.

Interfaces:
  subscribes  movements              (sgim_msgs/Movement)
  publishes   competences            (sgim_msgs/Competence)
  serves      register_demonstration (sgim_msgs/srv/RegisterDemonstration), explorer_ready
  action      reach_goal             (sgim_msgs/action/ReachGoal)
  client of   execute_action         (sgim_msgs/srv/ExecuteAction),
              choose_goal            (sgim_msgs/srv/ChooseGoal)
Parameters: the common ones and every LearnerConfig field; service_timeout, service_retries,
goal_timeout.
"""

from __future__ import annotations

from typing import Any

from sgim_msgs.action import ReachGoal
from sgim_msgs.msg import Competence
from sgim_msgs.srv import ChooseGoal, ExecuteAction, RegisterDemonstration
from sgim_nodes.bag.record_checks import teaching_signature_problem
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.core.competence import start_distance
from sgim_nodes.core.environment import MovementResult
from sgim_nodes.core.goal_reaching import GoalAttempt, probe_scale_for
from sgim_nodes.core.random_streams import component_rng
from sgim_nodes.nodes.graph_startup import call_bounded
from sgim_nodes.nodes.movement_memory import MOVEMENTS, MovementMemory
from sgim_nodes.nodes.ros_glue import (
    ACTS,
    PROCESS_CODES,
    AsyncNode,
    JobServer,
    check_vector,
    declare_learner,
    floats,
    learner_node_params,
    vec,
    world_scale,
)
from sgim_nodes.nodes.sim_client import EXECUTE, SIM_CLIENT_PARAMS, SimClient
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import action_server, calls, declared, publishes, serves
from sgim_ros.params import Param, positive
from sgim_ros.ready import serve_ready

PARAMS = learner_node_params(
    *SIM_CLIENT_PARAMS,
    Param("goal_timeout", 600.0, "seconds to wait for the goal generator's answer to "
          "choose_goal (it waits for the competences of the goals attempted before)", positive,
          read_only=False),
)

COMPETENCES, CHOOSE = publishes("competences"), calls("choose_goal")
READY, REGISTER = serves("explorer_ready"), serves("register_demonstration")
REACH = action_server("reach_goal")
INTERFACES = declared(COMPETENCES, CHOOSE, READY, REGISTER, REACH, MOVEMENTS, EXECUTE)


class JobRefused(ValueError):
    """A reach_goal job that cannot run (bad request, or no goal to attempt): aborted."""


class LowLevelExplorer(AsyncNode):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("low_level_explorer", **node_options)
        values, self.config = declare_learner(self, PARAMS)
        self.action_size, self.outcome_size = values["action_size"], values["outcome_size"]
        self.rng = component_rng(values["seed"], "explorer")
        self.acts = values["learner"] == ACTS
        self.scale = world_scale(values)
        self.distances = self.config.distances(self.scale)
        self.probe_scale = probe_scale_for(self.config, self.scale, self.action_size)
        self._report_at = 0  # the job's movements at which its next feedback is due
        self.memory = MovementMemory(self, self.config, self.action_size, self.outcome_size,
                                     self.scale)
        if values["resume_from"]:
            self.memory.resume(resume_point(values["resume_from"], self.config,
                                 values["resume_segments"]))
        self.goal_timeout = values["goal_timeout"]
        self.goal_client = CHOOSE.create(self)
        # A missed movement would stall every reach job that waits for it, and the first job
        # must find the goal generator (sgim_ros/ready.py).
        serve_ready(self, READY, {"movements": self.memory.subscription},
                    servers={"choose_goal": self.goal_client})
        self.sim = SimClient(self, values)
        self._competences = COMPETENCES.create(self)
        REGISTER.create(self, self._register)
        self.jobs = JobServer(self, REACH, self._attempt)

    def _register(self, request: RegisterDemonstration.Request,
                  response: RegisterDemonstration.Response):
        demo = request.demonstration
        # The arbiter checked it; it must still be a teacher's of this run (signed).
        problem = teaching_signature_problem("demonstrations", demo, self.memory.gate.limits)
        if problem is not None:
            response.accepted, response.message = False, problem.detail
            self.get_logger().error(f"refused demonstration {demo.index}: {problem.detail}")
            return response
        outcome = vec(demo.outcome)
        # Only an outcome the memory will take is measured: a NaN one stopped the nearest-
        # neighbour search, and the node, once the memory held a tree (found by fuzzing).
        usable = not check_vector(demo.outcome, self.outcome_size, "demonstration outcome")
        before = self.memory.memory.closest_distance(outcome) if usable else float("inf")
        why = self.memory.add_demonstration(vec(demo.action), outcome)
        response.accepted, response.message = not why, why
        if not why:
            response.closest_distance = start_distance(before, outcome, self.scale.centre)
        if why:
            self.get_logger().error(f"refused demonstration {demo.index}: {why}")
        return response

    async def _attempt(self, handle) -> ReachGoal.Result:
        """The job: goals chosen and attempted until the cap, max_goals or a cancel."""
        request: ReachGoal.Goal = handle.request
        result = ReachGoal.Result(competence=-1.0)
        self._report_at = request.report_after  # one job at a time
        try:
            self._check(request)
            await self.memory.reached(request.movements_before)
            if len(request.chosen.point):  # SGIM-ACTS's emulation: the teacher's outcome
                await self._reach(handle, request, result, request.chosen, False,
                                  aim=vec(request.demonstrated),
                                  start=request.chosen_start_distance)
            while not (len(request.chosen.point) or handle.is_cancel_requested
                       or result.movements_used >= request.max_movements
                       or (request.max_goals and result.goals_attempted >= request.max_goals)):
                demonstrated = list(request.demonstrated) if not result.goals_attempted else []
                goal = await self._choose(request, result, demonstrated)
                start = None
                if self.acts:
                    point = vec(goal.point)
                    start = start_distance(self.memory.memory.closest_distance(point), point,
                                           self.scale.centre)
                    if goal.strategy != "autonomous":  # the arbiter asks the teacher
                        result.social, result.social_start_distance = goal, start
                        break
                await self._reach(handle, request, result, goal, bool(demonstrated),
                                  start=start)
                if demonstrated or not result.goal_movements:
                    break  # a demonstrated goal is the job's only one; a goal cut at once ends it
        except JobRefused as error:
            self.get_logger().error(f"reach_goal job refused: {error}")
            handle.abort()
            return ReachGoal.Result(competence=-1.0)
        result.cancelled = bool(handle.is_cancel_requested)
        return result

    def _check(self, request: ReachGoal.Goal) -> None:
        why = ""
        if request.max_movements < 1:
            why = "max_movements must be at least 1 (the job's movement cap)"
        elif len(request.demonstrated):
            why = check_vector(request.demonstrated, self.outcome_size, "demonstrated goal",
                               bound=1.0)
        if not why and len(request.chosen.point):
            why = (check_vector(request.chosen.point, self.outcome_size, "chosen goal", 1.0)
                   or ("" if len(request.demonstrated) else
                       "a chosen goal (an emulation) needs the teacher's outcome to reach, "
                       "in demonstrated"))
        if not why and request.movements_before < self.memory.count:
            why = (f"the job starts after movement {request.movements_before}, but the run is "
                   f"at movement {self.memory.count}: not this run's arbiter")
        if why:
            raise JobRefused(why)

    async def _choose(self, request: ReachGoal.Goal, result: ReachGoal.Result,
                      demonstrated: list[float]):
        """The next goal (a Goal), once the tree holds every goal attempted before it."""
        reply = await call_bounded(self, self.goal_client, ChooseGoal.Request(
            movement_index=request.movements_before + result.movements_used,
            min_goal_count=request.goals_before + result.goals_attempted,
            demonstrated=demonstrated), "choose_goal", self.goal_timeout, fatal=False)
        if reply is None:
            raise JobRefused(f"no answer from choose_goal after {self.goal_timeout:g} s: is "
                             "the goal_generator node running?")
        if not reply.ok:
            raise JobRefused(f"the goal generator chose no goal: {reply.message}")
        return reply.goal

    async def _reach(self, handle, request: ReachGoal.Goal, result: ReachGoal.Result, chosen,
                     demonstrated: bool, aim=None, start: float | None = None) -> None:
        """Attempt one goal (``aim``, by default the chosen one) up to the job's cap or a
        cancel; its competence published and the result updated (the job's counts, and this
        goal as its last). ``start`` given (SGIM-ACTS): the competence is measured at the
        chosen goal against this distance, over every movement of the attempt."""
        goal = vec(chosen.point) if aim is None else aim
        attempt = GoalAttempt(goal, self.memory.memory, self.memory.inverse_model, self.config,
                              self.scale, self.rng, self.action_size, self.probe_scale)
        measured = None
        if start is not None:
            from sgim_nodes.core.competence import NearestOutcome

            measured = NearestOutcome(vec(chosen.point))
        used = 0
        while not (attempt.done or handle.is_cancel_requested
                   or result.movements_used + used >= request.max_movements):
            action, label = attempt.next_action()
            index = request.movements_before + result.movements_used + used + 1
            response = await self.sim.execute(ExecuteAction.Request(
                action=floats(action), process=PROCESS_CODES[label], movement_index=index,
                goal=floats(goal), goal_index=chosen.index, record=True))
            used += 1
            await self.memory.reached(index)
            outcome = vec(response.outcome) if len(response.outcome) else None
            moved = MovementResult(outcome, response.status)
            if measured is not None:
                measured.observe(moved)
            attempt.observe(action, moved)
        if measured is not None:  # SGIM-ACTS: at the chosen goal
            goal, best = measured.point, measured.outcome
        else:
            goal, best, start = goal, attempt.best_outcome, attempt.start_distance
        result.movements_used += used
        result.goal, result.goal_index = floats(goal), chosen.index
        result.goal_movements, result.finished = used, attempt.done
        result.reached = floats(best)
        result.competence = self.distances.competence(goal, best, start)
        if used > 0:  # an attempted goal, even an interrupted one, counts for the interest
            if result.movements_used >= self._report_at:  # only where the arbiter reports
                handle.publish_feedback(ReachGoal.Feedback(movements_done=result.movements_used))
                self._report_at = (result.movements_used + request.report_every
                                   if request.report_every else 0)
            result.goals_attempted += 1
            self._competences.publish(Competence(
                stamp=self.get_clock().now().to_msg(), goal_index=chosen.index,
                movement_index=request.movements_before + result.movements_used,
                goal=result.goal, reached=result.reached,
                competence=result.competence, movements_used=used,
                from_demonstration=demonstrated, strategy=chosen.strategy))


ENTRY = NodeEntry(LowLevelExplorer)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
