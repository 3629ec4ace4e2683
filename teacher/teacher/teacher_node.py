"""teacher: the automatic teacher, one demonstration every P movements.

It follows the learner through the movement stream (the outcomes of its own movements, see
core/teaching.py, and the count) and, at the run's start and at every P-th movement, publishes
a demonstration drawn by the core Teacher among the teaching-set goals the learner has not
reached by itself, or an empty one when every goal is reached, so that an arbiter waiting at
that boundary goes on. Its random stream "teacher"
makes its choices those of the single-process runner for the same seed.

Interfaces:
  subscribes  movements, run_status
  publishes   demonstrations (sgim_msgs/Demonstration)
Parameters: seed, demonstration_period, tolerance_noise, outcome_noise, teaching_set.
"""

from __future__ import annotations

import numpy as np
from rclpy.node import Node

from sgim_msgs.msg import Demonstration, Movement, RunStatus
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.bag.validation import Limits, LiveGate
from sgim_nodes.core.environment import PROCESS_CODES
from sgim_nodes.core.random_streams import component_rng
from sgim_nodes.core.teaching import (
    DEFAULT_TOLERANCE_NOISE,
    OWN_PROCESSES,
    PAPER_PERIOD,
    Teacher,
)
from sgim_nodes.nodes.ros_glue import floats, run_node, vec
from sgim_ros import qos
from sgim_ros.params import Param, at_least, declare, non_negative, positive
from sim_bridge.data_files import load_teaching_set
from sim_bridge.scaling import OUTCOME_NOISE

OWN_CODES = {PROCESS_CODES[label] for label in OWN_PROCESSES}
PARAMS = (
    Param("seed", 0, "seed of the run (the teacher uses its stream 'teacher')", at_least(0)),
    Param("demonstration_period", PAPER_PERIOD, "movements between demonstrations",
          at_least(1)),
    Param("tolerance_noise", DEFAULT_TOLERANCE_NOISE, "a teaching goal counts as reached "
          "within this many units of the world's outcome noise", non_negative),
    Param("outcome_noise", OUTCOME_NOISE, "the world's outcome noise (outcome units)",
          positive),
    Param("teaching_set", "", "teaching-set file (.npz); empty: the packaged one"),
    Param("movements", 0, "the run's movement budget, to validate run statuses (0: unknown)",
          non_negative),
    Param("resume_from", "", "run folder to resume (see sgim_nodes/bag/resume.py)"),
    Param("resume_segments", 0, "how many of its recordings to read (0: all)", at_least(0)),
)


class TeacherNode(Node):
    def __init__(self) -> None:
        super().__init__("teacher")
        p = declare(self, PARAMS)
        ts = load_teaching_set(p["teaching_set"] or None)
        self.teacher = Teacher(ts.actions, ts.outcomes, component_rng(p["seed"], "teacher"),
                               p["demonstration_period"],
                               p["tolerance_noise"] * p["outcome_noise"])
        self.reached: list[np.ndarray] = []
        self.total: int | None = None
        self.given = 0
        self.answered: set[int] = set()
        # Valid records only (bag/validation.py): a rogue movement moves neither the count
        # nor what the learner has reached; a rogue run status does not end the teaching.
        self.gate = LiveGate(self.get_logger().error, Limits(
            action_size=ts.actions.shape[1], outcome_size=ts.outcomes.shape[1],
            budget=p["movements"], teaching_set_size=len(ts.actions)))
        self._latest_row: int | None = None  # where movement `count` is in `reached`
        if p["resume_from"]:
            point = resume_point(p["resume_from"], limit=p["resume_segments"])
            self.reached = list(point.own_outcomes)
            self.gate.movements.count, self.answered = point.count, set(point.demonstration_turns)
            self.given = point.demonstrations_given
        self._out = self.create_publisher(Demonstration, "demonstrations", qos.RECORDS)
        self.create_subscription(Movement, "movements", self._on_movement, qos.RECORDS)
        self.create_subscription(RunStatus, "run_status", self._on_status, qos.RECORDS)
        self.get_logger().info(f"{len(ts.actions)} teaching entries, period "
                               f"{p['demonstration_period']}")

    @property
    def count(self) -> int:
        return self.gate.movements.count

    def _on_status(self, msg: RunStatus) -> None:
        if self.gate.check("run_status", msg):
            return
        self.total = msg.total_movements
        self._maybe_teach()

    def _on_movement(self, msg: Movement) -> None:
        verdict = self.gate.admit_movement(msg)
        if not verdict.ok:
            return
        ok = msg.status == Movement.STATUS_OK and msg.process in OWN_CODES
        if verdict.supersedes and self._latest_row is not None:  # a re-execution replaces
            del self.reached[self._latest_row]  # the latest movement's outcome
        self._latest_row = None
        if ok:
            self._latest_row = len(self.reached)
            self.reached.append(vec(msg.outcome))
        if not verdict.supersedes:
            self._maybe_teach()

    def _maybe_teach(self) -> None:
        k = self.count
        if self.total is None or k >= self.total or k in self.answered:
            return
        if not self.teacher.due(k):
            return
        self.answered.add(k)
        reached = np.array(self.reached).reshape(-1, self.teacher.outcomes.shape[1])
        demo = self.teacher.choose(reached)
        msg = Demonstration(stamp=self.get_clock().now().to_msg(), movement_index=k,
                            teaching_set_index=-1, source="automatic")
        if demo is not None:
            self.given += 1
            msg.index, msg.teaching_set_index = self.given, demo.index
            msg.action, msg.outcome = floats(demo.action), floats(demo.outcome)
            self.get_logger().info(f"demonstration {self.given} at movement {k}: entry "
                                   f"{demo.index}, outcome {np.round(demo.outcome, 3)}")
        else:
            self.get_logger().info(f"nothing left to demonstrate at movement {k}")
        self._out.publish(msg)


def main(args: list[str] | None = None) -> int:
    return run_node(TeacherNode, args)


if __name__ == "__main__":
    raise SystemExit(main())
