"""low_level_explorer: reaches one goal at a time (inverse model, Nelder-Mead, exploration).

Each `reach_goal` job is one core GoalAttempt driven movement by movement: its actions are
executed through the simulator's `execute_action` service, and the job waits until each
movement has come back on the `movements` stream into its memory before the next step, as the
single-process learner would. A cancel (the arbiter preempting for a demonstration) is
honoured at the next movement boundary; the movement under way always completes. The
attempt's competence is published on `competences` whenever it spent a movement (marked
from_demonstration for a demonstrated outcome adopted as a goal: a goal-only demonstration);
the result says whether the attempt ended by itself or was cut.

Interfaces:
  subscribes  movements              (sgim_msgs/Movement)
  publishes   competences            (sgim_msgs/Competence)
  serves      register_demonstration (sgim_msgs/srv/RegisterDemonstration)
  action      reach_goal             (sgim_msgs/action/ReachGoal)
  client of   execute_action         (sgim_msgs/srv/ExecuteAction)
Parameters: the common ones and every LearnerConfig field; service_timeout.
"""

from __future__ import annotations

from sgim_msgs.action import ReachGoal
from sgim_msgs.msg import Competence
from sgim_msgs.srv import ExecuteAction, RegisterDemonstration
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.core.competence import competence, start_distance
from sgim_nodes.core.environment import MovementResult
from sgim_nodes.core.goal_reaching import GoalAttempt, probe_scale_for
from sgim_nodes.core.random_streams import component_rng
from sgim_nodes.nodes.movement_memory import MovementMemory
from sgim_nodes.nodes.ros_glue import (
    PROCESS_CODES,
    AsyncNode,
    JobServer,
    check_vector,
    declare_learner,
    floats,
    learner_node_params,
    run_node,
    vec,
    world_scale,
)
from sgim_nodes.nodes.sim_client import SIM_CLIENT_PARAMS, SimClient
from sgim_ros import qos
from sgim_ros.ready import serve_ready

PARAMS = learner_node_params(*SIM_CLIENT_PARAMS)


class LowLevelExplorer(AsyncNode):
    def __init__(self) -> None:
        super().__init__("low_level_explorer")
        values, self.config = declare_learner(self, PARAMS)
        self.action_size, self.outcome_size = values["action_size"], values["outcome_size"]
        self.rng = component_rng(values["seed"], "explorer")
        self.scale = world_scale(values)
        self.distances = self.config.distances(self.scale)
        self.probe_scale = probe_scale_for(self.config, self.scale, self.action_size)
        self.memory = MovementMemory(self, self.config, self.action_size, self.outcome_size,
                                     self.scale)
        if values["resume_from"]:
            self.memory.resume(resume_point(values["resume_from"], self.config,
                                 values["resume_segments"]))
        # A missed movement would stall every reach job that waits for it (sgim_ros/ready.py).
        serve_ready(self, "explorer_ready", {"movements": self.memory.subscription})
        self.sim = SimClient(self, values)
        self._competences = self.create_publisher(Competence, "competences", qos.RECORDS)
        self.create_service(RegisterDemonstration, "register_demonstration", self._register)
        self.jobs = JobServer(self, ReachGoal, "reach_goal", self._attempt)

    def _register(self, request: RegisterDemonstration.Request,
                  response: RegisterDemonstration.Response):
        demo = request.demonstration
        outcome = vec(demo.outcome)
        before = self.memory.memory.closest_distance(outcome) if outcome.shape == (
            self.outcome_size,) else float("inf")
        why = self.memory.add_demonstration(vec(demo.action), outcome)
        response.accepted, response.message = not why, why
        if not why:
            response.closest_distance = start_distance(before, outcome, self.scale.centre)
        if why:
            self.get_logger().error(f"refused demonstration {demo.index}: {why}")
        return response

    async def _attempt(self, handle) -> ReachGoal.Result:
        request: ReachGoal.Goal = handle.request
        result = ReachGoal.Result(competence=-1.0)
        why = check_vector(request.goal, self.outcome_size, "goal", bound=1.0)
        if not why and request.movements_before < self.memory.count:
            why = (f"the job starts after movement {request.movements_before}, but the run is "
                   f"at movement {self.memory.count}: not this run's arbiter")
        if why:
            self.get_logger().error(f"refused goal {request.goal_index}: {why}")
            handle.abort()
            return result
        await self.memory.reached(request.movements_before)
        goal = vec(request.goal)
        attempt = GoalAttempt(goal, self.memory.memory, self.memory.inverse_model, self.config,
                              self.scale, self.rng, self.action_size, self.probe_scale)
        used = 0
        while not attempt.done:
            if handle.is_cancel_requested:
                result.cancelled = True
                break
            if request.max_movements and used >= request.max_movements:
                break
            action, label = attempt.next_action()
            index = request.movements_before + used + 1
            response = await self.sim.execute(ExecuteAction.Request(
                action=floats(action), process=PROCESS_CODES[label], movement_index=index,
                goal=floats(goal), goal_index=request.goal_index, record=True))
            used += 1
            await self.memory.reached(index)
            outcome = vec(response.outcome) if len(response.outcome) else None
            attempt.observe(action, MovementResult(outcome, response.status))
            handle.publish_feedback(ReachGoal.Feedback(movements_done=used,
                                                       best_distance=attempt.best_distance))
        result.movements_used = used
        result.finished = attempt.done
        result.reached = floats(attempt.best_outcome)
        if attempt.best_outcome is not None:
            reference = (attempt.start_distance
                         if self.config.competence_reference == "memory"
                         else self.distances.competence_radius)
            result.competence = competence(goal, attempt.best_outcome, reference,
                                           self.distances.success_tolerance,
                                           self.distances.competence_floor)
        if used > 0:  # an attempted goal, even an interrupted one, counts for the interest
            self._competences.publish(Competence(
                stamp=self.get_clock().now().to_msg(), goal_index=request.goal_index,
                movement_index=request.movements_before + used, goal=floats(goal),
                reached=result.reached, competence=result.competence, movements_used=used,
                from_demonstration=request.demonstrated))
        return result


def main(args: list[str] | None = None) -> int:
    return run_node(LowLevelExplorer, args)


if __name__ == "__main__":
    raise SystemExit(main())
