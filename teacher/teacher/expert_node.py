"""expert: one of SGIM-ACTS's teachers (issue 33), answering the learner's requests.

Unlike the automatic teacher (teacher_node.py), which decides when to speak and what the
learner has not reached, an expert only answers: the learner chooses whom to ask, about what
goal, and whether it wants the movement (mimicry) or only where it lands (emulation). Each
expert is a node of its own, in the namespace of its name (/centre/expert, /west/expert, ...),
and answers the HelpRequests that name it with its demonstration nearest the asked goal
(core/experts.py Expert): the action when asked for it, and the outcome its own copy of the
world gives that action; or an empty Demonstration, "none there", when its nearest
demonstration lies beyond its radius (the request still cost the learner its price).

What it knows: the rows of the world's teaching set in its `part` of the lake ("all",
"parts:basin+north+east", ...), shown with Gaussian `precision` (action units; a rough expert's
movements land off its teaching outcomes), within `radius_size` of a goal. With `part` empty
it is the fishing world's expert of its name (core/experts.py FISHING_EXPERTS: centre, west,
rough). Its random stream (random_streams.member_rng "experts", its name) and its world (the
run's stream "teacher-world") are the single-process runner's: the same requests in the same
order get the same answers.

Interfaces (absolute names: every expert shares the run's record topics):
  subscribes  /help_requests (HelpRequest: those whose `teacher` is its name), /run_status
  publishes   /demonstrations (Demonstration: source "expert:NAME", help_request = the ask's
              index, movement_index = the ask's, teaching_set_index the world's row or -1)
  serves      expert_ready (RecorderReady, in its namespace): a request published before the
              expert's subscription matched would be lost (the records' QoS is volatile), so
              the arbiter asks it before the run's first movement (sgim_ros/ready.py)
Parameters: name, part, precision, radius_size, seed, noise, teaching_set, action_size,
outcome_size, outcome_noise, movements.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rclpy.node import Node

from sgim_msgs.msg import Demonstration, HelpRequest, RunStatus
from sgim_nodes.bag.record_checks import Limits, expert_source
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.experts import FISHING_EXPERTS, ExpertAnswer, ExpertSpec, build_experts
from sgim_nodes.core.random_streams import world_seed
from sgim_nodes.core.strategies import check_teacher_name
from sgim_nodes.core.teaching import GOAL_ONLY, MEANS_AND_GOAL, MEANS_ONLY
from sgim_nodes.nodes.ros_glue import COMMON_PARAMS, floats, vec, world_scale
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import declared, publishes, serves, subscribes
from sgim_ros.params import Param, ParameterError, declare, non_negative
from sgim_ros.ready import serve_ready
from sim_bridge.data_params import TEACHING_SET_FILE
from sim_bridge.fishing_world import DEFAULT_NOISE, FishingWorld
from sim_bridge.lake import Lake
from teacher.teaching_set import load_checked

WORLD_EXPERTS = {spec.name: spec for spec in FISHING_EXPERTS}

PARAMS = (
    *(p for p in COMMON_PARAMS if p.name not in ("learner", "resume_from", "resume_segments")),
    Param("name", "", "the teacher's name, as requests name it; empty: the node's namespace "
          "(/west -> west)"),
    Param("part", "", "which demonstrations it knows: 'all', 'parts:<a>+<b>' (the lake's "
          "basin, north, east, west, south, pond), 'low:<axis>' or 'high:<axis>'; empty: the "
          "fishing world's expert of its name (core/experts.py: centre, west, rough)"),
    Param("precision", 0.0, "standard deviation of the perturbation of the actions it shows, "
          "in action units (with part set)", non_negative),
    Param("radius_size", 0.0, "it answers 'none there' beyond this distance from its nearest "
          "demonstration, as a fraction of the outcome box's side; 0: no limit (with part "
          "set)", non_negative),
    Param("noise", DEFAULT_NOISE, "motor-command noise of its own world, where its shown "
          "actions land", non_negative),
    Param("teaching_set", "", "teaching-set file (.npz); empty: the packaged one",
          TEACHING_SET_FILE),
    Param("movements", 0, "the run's movement budget, to validate requests (0: unknown)",
          non_negative),
)


def expert_spec(name: str, part: str, precision: float, radius_size: float) -> ExpertSpec:
    """The expert the parameters describe: the world's of that name when `part` is empty."""
    if not part:
        if precision or radius_size:
            raise ParameterError("precision and radius_size describe an expert of your own: "
                                 "set part too, or leave all three to the world's expert "
                                 f"{name!r}")
        if name not in WORLD_EXPERTS:
            raise ParameterError(f"the fishing world has no expert {name!r} (it has "
                                 f"{', '.join(WORLD_EXPERTS)}): set part, precision and "
                                 "radius_size")
        return WORLD_EXPERTS[name]
    return ExpertSpec(name, part, precision, radius_size or math.inf)

# The node lives in its teacher's namespace (/NAME); the run's topics are in the root one.
DEMONSTRATIONS, REQUESTS = publishes("/demonstrations"), subscribes("/help_requests")
STATUS, READY = subscribes("/run_status"), serves("expert_ready")
INTERFACES = declared(DEMONSTRATIONS, REQUESTS, STATUS, READY)


class ExpertNode(Node):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("expert", **node_options)
        p = declare(self, PARAMS)
        name = p["name"] or self.get_namespace().strip("/").rsplit("/", 1)[-1]
        try:
            self.teacher_name = check_teacher_name(name)
            spec = expert_spec(name, p["part"], p["precision"], p["radius_size"])
        except ValueError as error:
            raise ParameterError(f"expert: {error}") from error
        ts = load_checked(p["teaching_set"], p["action_size"], p["outcome_size"])
        part_of = Lake().part_of_outcome
        self.world = FishingWorld(seed=world_seed(p["seed"], "teacher-world"), noise=p["noise"])
        try:
            [self.expert] = build_experts([spec], ts.actions, ts.outcomes, p["seed"],
                                          world_scale(p).size, lambda: self.world,
                                          part_of).values()
        except ValueError as error:
            raise ParameterError(f"expert {name!r}: {error}") from error
        self.source = expert_source(name)
        self.shown = 0
        self.answered: set[int] = set()
        self.gate = LiveGate(self.get_logger().error, Limits(
            p["action_size"], p["outcome_size"], budget=p["movements"],
            teaching_set_size=len(ts.actions)))
        self._out = DEMONSTRATIONS.create(self)
        requests = REQUESTS.create(self, self._on_request)
        # A request missed before the DDS match would leave the learner waiting: the arbiter
        # asks <namespace>/expert_ready before its first movement (sgim_ros/ready.py).
        serve_ready(self, READY, {"help_requests": requests})
        STATUS.create(self, self._on_status)
        radius = ("no radius" if math.isinf(self.expert.radius)
                  else f"radius {self.expert.radius:g}")
        self.get_logger().info(f"expert {name}: {len(self.expert.rows)} demonstrations "
                               f"({spec.part}), "
                               f"precision {spec.precision:g}, {radius}")

    def _on_status(self, msg: RunStatus) -> None:
        if self.gate.check("run_status", msg):
            return
        if msg.state == RunStatus.STATE_FINISHED:
            self.get_logger().info(f"run finished: {len(self.answered)} requests answered, "
                                   f"{self.shown} with a demonstration")

    def _on_request(self, msg: HelpRequest) -> None:
        if msg.teacher != self.teacher_name or self.gate.check("help_requests", msg):
            return
        if msg.index in self.answered:
            self.get_logger().warning(f"help request {msg.index} again: answered once only")
            return
        self.answered.add(msg.index)
        wants_action = msg.content != GOAL_ONLY
        answer = self.expert.answer(vec(msg.goal), wants_action)
        self._out.publish(self.demonstration(msg, answer, wants_action))

    def demonstration(self, ask: HelpRequest, answer: ExpertAnswer | None,
                      wants_action: bool) -> Demonstration:
        """The answer as a Demonstration: what was asked for, of what the expert has. Its
        action with no outcome (its cast landed on land) is shown means-only; an emulation
        answer without an outcome shows nothing, as "none there"."""
        msg = Demonstration(stamp=self.get_clock().now().to_msg(),
                            movement_index=ask.movement_index, teaching_set_index=-1,
                            source=self.source, help_request=ask.index,
                            content=MEANS_AND_GOAL if wants_action else GOAL_ONLY)
        action = None if answer is None else answer.action
        outcome = None if answer is None else answer.outcome
        if action is None and outcome is None:  # none there, or an emulation's cast on land
            why = ("none there" if answer is None else
                   f"entry {answer.index}'s cast gave no outcome to show")
            self.get_logger().info(f"help request {ask.index}: {why} (goal "
                                   f"{np.round(vec(ask.goal), 3)})")
            return msg
        if action is not None and outcome is None:
            msg.content = MEANS_ONLY
        self.shown += 1
        msg.index = self.shown
        msg.teaching_set_index = answer.index
        msg.action = [] if action is None else floats(action)
        msg.outcome = [] if outcome is None else floats(outcome)
        self.get_logger().info(f"help request {ask.index}: entry {msg.teaching_set_index} "
                               f"({msg.content}), {answer.distance:.3f} from the goal")
        return msg

    def destroy_node(self) -> None:
        self.world.close()
        super().destroy_node()


ENTRY = NodeEntry(ExpertNode)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
