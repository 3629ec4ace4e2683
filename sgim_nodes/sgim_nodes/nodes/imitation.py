"""imitation: repeats a demonstrated action with small random variations.

Each `imitate` job is one core Imitation (a_demo + a_rand, |a_rand| < imitation_epsilon)
driven movement by movement through the simulator's `execute_action` service, recorded as
imitation movements aimed at the demonstrated outcome. A means-only demonstration (issue 14)
comes without its outcome: its imitation aims at no goal (the movements' goal is empty) and
has no best outcome, as the core's. SGIM-ACTS's mimicry gives `measure_at`, the goal it
chose: the best outcome is then the one nearest that goal (core/competence.NearestOutcome),
whatever the demonstration showed. A cancel is honoured at the next movement boundary.

Interfaces:
  subscribes  movements      (sgim_msgs/Movement; validated: the run's count, to refuse a job
                              that does not start at it)
  action      imitate        (sgim_msgs/action/Imitate)
  client of   execute_action (sgim_msgs/srv/ExecuteAction)
Parameters: the common ones, imitation_count and imitation_epsilon of LearnerConfig,
service_timeout.
"""

from __future__ import annotations

from typing import Any

from sgim_msgs.action import Imitate
from sgim_msgs.msg import Movement
from sgim_msgs.srv import ExecuteAction
from sgim_nodes.bag.record_checks import Limits
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.environment import MovementResult
from sgim_nodes.core.imitation import Imitation
from sgim_nodes.core.random_streams import component_rng
from sgim_nodes.nodes.ros_glue import (
    AsyncNode,
    JobServer,
    check_vector,
    declare_learner,
    floats,
    learner_node_params,
    vec,
)
from sgim_nodes.nodes.sim_client import EXECUTE, SIM_CLIENT_PARAMS, SimClient
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import action_server, declared, serves, subscribes
from sgim_ros.ready import serve_ready

PARAMS = learner_node_params(*SIM_CLIENT_PARAMS)
MOVEMENTS, READY, IMITATE = (subscribes("movements"), serves("imitation_ready"),
                              action_server("imitate"))
INTERFACES = declared(MOVEMENTS, READY, IMITATE, EXECUTE)


class ImitationNode(AsyncNode):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("imitation", **node_options)
        values, self.config = declare_learner(self, PARAMS)
        self.action_size, self.outcome_size = values["action_size"], values["outcome_size"]
        self.rng = component_rng(values["seed"], "imitation")
        # Valid movements only (bag/validation.py): the run's count, to refuse a job that
        # does not start at it.
        self.gate = LiveGate(self.get_logger().error,
                             Limits(self.action_size, self.outcome_size))
        if values["resume_from"]:
            self.gate.movements.count = resume_point(
                values["resume_from"], self.config, values["resume_segments"]).count
        serve_ready(self, READY, {"movements": MOVEMENTS.create(self, self.gate.admit_movement)})
        self.sim = SimClient(self, values)
        self.jobs = JobServer(self, IMITATE, self._run)

    async def _run(self, handle) -> Imitate.Result:
        request: Imitate.Goal = handle.request
        result = Imitate.Result(best_distance=float("inf"))
        why = (check_vector(request.action, self.action_size, "demonstrated action", 1.0)
               or (check_vector(request.outcome, self.outcome_size, "demonstrated outcome")
                   if len(request.outcome) else "")
               or (check_vector(request.measure_at, self.outcome_size, "goal to measure at",
                                1.0) if len(request.measure_at) else ""))
        count = self.gate.movements.count
        if not why and request.movements_before < count:
            why = (f"the job starts after movement {request.movements_before}, but the run is "
                   f"at movement {count}: not this run's arbiter")
        if why:
            self.get_logger().error(f"refused an imitation: {why}")
            handle.abort()
            return result
        count = request.repetitions or self.config.imitation_count
        goal = vec(request.outcome) if len(request.outcome) else None  # None: means-only
        job = Imitation(vec(request.action), goal, count,
                        self.config.imitation_epsilon, self.rng)
        measured = None
        if len(request.measure_at):
            from sgim_nodes.core.competence import NearestOutcome

            measured = NearestOutcome(vec(request.measure_at))
        while not job.done:
            if handle.is_cancel_requested:
                result.cancelled = True
                break
            action, _ = job.next_action()
            response = await self.sim.execute(ExecuteAction.Request(
                action=floats(action), process=Movement.PROCESS_IMITATION,
                movement_index=request.movements_before + job.movements + 1,
                goal=list(request.outcome), record=True))
            outcome = vec(response.outcome) if len(response.outcome) else None
            moved = MovementResult(outcome, response.status)
            if measured is not None:
                measured.observe(moved)
            job.observe(action, moved)
            handle.publish_feedback(Imitate.Feedback(movements_done=job.movements))
        result.movements_used = job.movements
        best = job if measured is None else None
        result.best_outcome = floats(job.best_outcome if best else measured.outcome)
        result.best_distance = job.best_distance if best else measured.distance
        return result


ENTRY = NodeEntry(ImitationNode)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
