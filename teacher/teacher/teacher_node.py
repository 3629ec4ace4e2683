"""teacher: the automatic teacher, one demonstration every P movements, or when asked.

With `timing: period` (the paper's), at the run's start and at every P-th movement it
publishes a demonstration drawn by the core Teacher among the teaching-set goals the learner
has not reached, or an empty one when every goal is reached, so that an arbiter waiting at that
boundary goes on. With `timing: on-request` (issue 14, core/help_request.py) it speaks only to
answer the learner's HelpRequest: the unreached entry nearest the goal asked about
(Teacher.answer), at the count of the ask, once its mirrored memory is there. What it shows is
`demonstration_content` (core/teaching.py, Demonstration.shown): the action and its outcome, the
outcome only (goal-only) or the action only (means-only); what is not shown is never published,
and only a pair shown whole enters the mirrored memory, as the learner's. "Reached" follows
`reached_rule` (core/teaching.py):
  ability        (default) the learner's inverse model, asked for the goal now, gives an
                 action whose cast lands within the tolerance of it. The teacher mirrors the
                 learner's memory as the evaluator does (the movement stream, its own
                 demonstrations placed where the learner took them, and any other teacher's
                 from `demonstrations_taken`), builds the same inverse model, and casts in its
                 OWN fishing world (seeded by the run's stream "teacher-world"): casts that
                 are never published, stored or counted.
  own-movements  one of the learner's own movements (goal-directed, exploration, random)
                 landed within the tolerance of it.
Its random stream "teacher" and its world's stream make its choices those of the
single-process runner for the same seed.
With `teacher_turns` (issue 33's comparison, core/teacher_turns.py) several teachers take the
turns, in the order named: each knows its part of the teaching set and shows it with its own
precision (SGIM-ACTS's experts: centre, west, rough); a rough teacher's cast that lands on no
water shows the action alone (means-only).
Every turn's judgement is recorded (issue 31): before the turn's demonstration it publishes one
TeacherCheck per teaching goal on `teacher_checks` (the goal, the action the learner's model
gave, where its world landed it or the learner's own outcome nearest it, the distance, the
tolerance, the verdict, the entry shown), from which an auditor redoes the turn; no learner
node reads them.

Interfaces:
  subscribes  movements, demonstrations_taken, run_status, help_requests (on-request only)
  publishes   teacher_checks (sgim_msgs/TeacherCheck), demonstrations (sgim_msgs/Demonstration)
Parameters: the common ones, the memory and inverse-model fields of LearnerConfig,
demonstration_period, reached_rule, teacher_choice, demonstration_content, timing,
tolerance_noise, noise (of the teacher's own world), teaching_set, movements, teacher_turns.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from builtin_interfaces.msg import Time
from rclpy.node import Node

from sgim_msgs.msg import Demonstration, HelpRequest, RunStatus, TeacherCheck
from sgim_nodes.bag.record_checks import Limits
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.help_request import ON_REQUEST
from sgim_nodes.core.learners import inverse_or_centre
from sgim_nodes.core.random_streams import component_rng, world_seed
from sgim_nodes.core.repeatable_casts import RepeatableCasts
from sgim_nodes.core.teaching import (
    ABILITY,
    MEANS_ONLY,
    OWN_PROCESSES,
    Teacher,
    Turn,
    learner_progress,
)
from sgim_nodes.core.teaching import (
    Demonstration as Shown,
)
from sgim_nodes.nodes.movement_memory import MOVEMENTS, MovementMemory
from sgim_nodes.nodes.ros_glue import (
    declare_learner,
    floats,
    learner_node_params,
    social_config,
    social_params,
    vec,
    world_scale,
)
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import declared, publishes, serves, subscribes
from sgim_ros.params import Param, ParameterError, non_negative
from sgim_ros.ready import serve_ready
from sim_bridge.data_params import TEACHING_SET_FILE
from sim_bridge.fishing_world import DEFAULT_NOISE, FishingWorld
from teacher.teaching_set import load_checked

AUTOMATIC = "automatic"  # Demonstration.source of this node's demonstrations
PARAMS = learner_node_params(
    *social_params("demonstration_period", "reached_rule", "teacher_choice",
                   "demonstration_content", "timing", "tolerance_noise"),
    Param("noise", DEFAULT_NOISE, "motor-command noise of the teacher's own world (the "
          "'ability' rule casts there)", non_negative),
    Param("teaching_set", "", "teaching-set file (.npz); empty: the packaged one",
          TEACHING_SET_FILE),
    Param("movements", 0, "the run's movement budget, to validate run statuses (0: unknown)",
          non_negative),
    Param("teacher_turns", "", "several teachers take the turns, in this order: "
          "comma-separated names of SGIM-ACTS's experts (centre, west, rough); empty: one "
          "teacher who knows the whole teaching set (core/teacher_turns.py)"),
)


def teacher_turns(p: dict, ts, tolerance: float):
    """The teachers of `teacher_turns`, each casting in its own copy of the teacher's world."""
    from sgim_nodes.core.teacher_turns import TeacherTurns, turn_specs
    from sim_bridge.lake import Lake

    try:
        specs = turn_specs("fishing", p["teacher_turns"])
        return TeacherTurns(specs, ts.actions, ts.outcomes, p["seed"],
                            p["demonstration_period"], tolerance, p["teacher_choice"],
                            lambda: FishingWorld(seed=world_seed(p["seed"], "teacher-world"),
                                                 noise=p["noise"]), Lake().part_of_outcome)
    except ValueError as error:
        raise ParameterError(f"parameter 'teacher_turns': {error}") from error

CHECKS, DEMONSTRATIONS = publishes("teacher_checks"), publishes("demonstrations")
TAKEN, STATUS = subscribes("demonstrations_taken"), subscribes("run_status")
REQUESTS = subscribes("help_requests", "timing on-request")
READY = serves("teacher_ready")
INTERFACES = declared(CHECKS, DEMONSTRATIONS, TAKEN, STATUS, REQUESTS, READY, MOVEMENTS)


class TeacherNode(Node):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("teacher", **node_options)
        p, config = declare_learner(self, PARAMS)
        ts = load_checked(p["teaching_set"], p["action_size"], p["outcome_size"])
        tolerance = p["tolerance_noise"] * p["outcome_noise"]
        social_config(p)  # the settings that go together, as the runner checks them
        if p["teacher_turns"]:
            self.teacher = teacher_turns(p, ts, tolerance)
        else:
            self.teacher = Teacher(ts.actions, ts.outcomes, component_rng(p["seed"], "teacher"),
                                   p["demonstration_period"], tolerance, p["teacher_choice"])
        self.rule = p["reached_rule"]
        self.choice = p["teacher_choice"]
        self.content = p["demonstration_content"]
        self.on_request = p["timing"] == ON_REQUEST
        self.requests: dict[int, HelpRequest] = {}  # asks waiting for the mirror to catch up
        self.action_size = p["action_size"]
        self.world = (FishingWorld(seed=world_seed(p["seed"], "teacher-world"),
                                   noise=p["noise"]) if self.rule == ABILITY else None)
        # Its casts for the whole run, as the runner's: an answer unchanged since the last
        # turn is not cast again (core/repeatable_casts.py).
        self.casts = RepeatableCasts(self.world) if self.world is not None else None
        self.total: int | None = None
        self.given = 0
        self.answered: set[int] = set()  # periodic turns (movement counts) taken
        self.answered_requests: set[int] = set()  # HelpRequest indices answered
        # Valid records only (bag/validation.py): a rogue movement moves neither the count
        # nor the mirrored memory; a rogue run status does not end the teaching.
        limits = Limits(action_size=ts.actions.shape[1], outcome_size=ts.outcomes.shape[1],
                        budget=p["movements"], teaching_set_size=len(ts.actions))
        self.gate = LiveGate(self.get_logger().error, limits)
        self.memory = MovementMemory(self, config, p["action_size"], p["outcome_size"],
                                     world_scale(p), limits)
        self.memory.after_store.append(lambda _msg: self._maybe_teach())
        if p["resume_from"]:
            point = resume_point(p["resume_from"], config, p["resume_segments"])
            self.memory.resume(point)
            self.answered = set(point.demonstration_turns)
            if p["teacher_turns"]:
                self.teacher.turn = len(self.answered)
            self.answered_requests = set(point.help_requests_answered)
            self.given = point.demonstrations_given
        # The arbiter waits for a publisher of both and for the recorder to match them
        # (nodes/graph_startup.py): no turn's checks are lost, the first one's included.
        self._checks, self._out = CHECKS.create(self), DEMONSTRATIONS.create(self)
        # The arbiter starts once these have matched (sgim_ros/ready.py): a missed movement
        # would leave the mirrored memory, and so the teacher's choice, behind the learner's.
        listened = {
            "movements": self.memory.subscription,
            "demonstrations_taken": TAKEN.create(self, self._on_taken),
            "run_status": STATUS.create(self, self._on_status)}
        if self.on_request:  # an ask missed would leave the learner waiting for its answer
            listened["help_requests"] = REQUESTS.create(self, self._on_request)
        serve_ready(self, READY, listened)
        when = ("on request" if self.on_request else
                f"period {p['demonstration_period']}")
        self.get_logger().info(f"{len(ts.actions)} teaching entries, {when}, reached rule "
                               f"{self.rule}, choice {p['teacher_choice']}, showing "
                               f"{self.content}")

    @property
    def count(self) -> int:
        return self.memory.count

    def _on_status(self, msg: RunStatus) -> None:
        if self.gate.check("run_status", msg):
            return
        self.total = msg.total_movements
        if msg.state == RunStatus.STATE_FINISHED:
            casts = (f"; casts made {self.casts.made}, kept {self.casts.saved}"
                     if self.casts is not None else "")
            self.get_logger().info(f"run finished: {self.given} demonstrations in "
                                   f"{len(self.answered)} turns ({self.rule} rule{casts})")
            return
        self._maybe_teach()

    def _on_taken(self, msg: Demonstration) -> None:
        """Another teacher's demonstration the learner took enters the mirrored memory; this
        teacher's own are stored when given (below), so that the judgement at a turn never
        waits on a message."""
        if self.gate.check("demonstrations_taken", msg) or msg.source == AUTOMATIC:
            return
        if len(msg.action) and len(msg.outcome):  # only a pair shown whole is stored
            self.memory.add_demonstration_after(msg.movement_index, vec(msg.action),
                                                vec(msg.outcome))

    def _on_request(self, msg: HelpRequest) -> None:
        if self.gate.check("help_requests", msg):
            return
        if msg.index in self.answered_requests or msg.index in self.requests:
            self.get_logger().warning(f"help request {msg.index} again: answered once only")
            return
        self.requests[msg.index] = msg
        self._maybe_teach()

    def _own_outcomes(self) -> np.ndarray:
        labels = np.asarray(self.memory.memory.labels)
        return self.memory.memory.outcomes[np.isin(labels, OWN_PROCESSES)]

    def _reached(self):
        model = self.memory.inverse_model
        return learner_progress(
            self.rule, lambda goal: inverse_or_centre(model, goal, self.action_size),
            self._own_outcomes, self.casts)

    def _maybe_teach(self) -> None:
        if self.on_request:
            self._maybe_answer()
            return
        k = self.count
        if self.total is None or k >= self.total or k in self.answered:
            return
        if not self.teacher.due(k):
            return
        self.answered.add(k)
        self._publish(self.teacher.decide(self._reached()), k)

    def _maybe_answer(self) -> None:
        """Answer each ask once the mirrored memory is at its count (the learner waits there,
        so the count never passes it; an ask the count has passed is not this run's)."""
        for index in sorted(self.requests):
            ask = self.requests[index]
            if ask.movement_index > self.count:
                return
            del self.requests[index]
            if ask.movement_index < self.count:
                self.get_logger().error(f"help request {index} asks at movement "
                                        f"{ask.movement_index}, but the learner is at "
                                        f"{self.count}: not this run's learner; ignored")
                continue
            self.answered_requests.add(index)
            self.get_logger().info(f"help request {index} at movement {self.count}, goal "
                                   f"{np.round(vec(ask.goal), 3)}")
            self._publish(self.teacher.decide(self._reached(), vec(ask.goal)), self.count,
                          index)

    def _publish_checks(self, turn: Turn, k: int, request: int, stamp: Time) -> None:
        """The turn's checks, one TeacherCheck per teaching goal, as the runner writes them
        (core/runner.py check_records): what an auditor redoes the turn from."""
        asked = floats(turn.asked)
        for check in turn.checks:
            self._checks.publish(TeacherCheck(
                stamp=stamp, movement_index=k, help_request=request, asked_goal=asked,
                rule=self.rule, choice=self.choice, entries=len(turn.checks),
                teaching_set_index=check.index, goal=floats(check.goal),
                action=floats(check.action), status=int(check.status),
                landed=floats(check.landed), own_outcomes=check.own_outcomes,
                distance=float(check.distance),
                tolerance=float(check.tolerance), reached=check.reached,
                chosen=check.index == turn.chosen))

    def _publish(self, turn: Turn, k: int, request: int = 0) -> None:
        """Publish the turn's checks, then show its demonstration (None: nothing left to
        show) as `demonstration_content` says."""
        stamp = self.get_clock().now().to_msg()
        self._publish_checks(turn, k, request, stamp)
        demo: Shown | None = turn.demonstration
        msg = Demonstration(stamp=stamp, movement_index=k,
                            teaching_set_index=-1, source=AUTOMATIC, content=self.content,
                            help_request=request)
        if demo is not None:
            self.given += 1
            action, outcome = demo.shown(self.content)
            msg.index, msg.teaching_set_index = self.given, demo.index
            msg.action = [] if action is None else floats(action)
            msg.outcome = [] if outcome is None else floats(outcome)
            if action is not None and outcome is None and self.content != MEANS_ONLY:
                msg.content = MEANS_ONLY  # a rough teacher's cast that landed nowhere
            if action is not None and outcome is not None:
                # The learner stores it right after movement k, as the single-process runner.
                self.memory.add_demonstration_after(k, action, outcome)
            by = f" by {demo.teacher}" if getattr(demo, "teacher", "") else ""
            landed = "none" if demo.outcome is None else np.round(demo.outcome, 3)
            self.get_logger().info(f"demonstration {self.given} at movement {k}{by}: entry "
                                   f"{demo.index}, outcome {landed}, showing {msg.content}")
        else:
            self.get_logger().info(f"nothing left to demonstrate at movement {k}")
        self._out.publish(msg)

    def destroy_node(self) -> None:
        if self.world is not None:
            self.world.close()
        super().destroy_node()


ENTRY = NodeEntry(TeacherNode)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
