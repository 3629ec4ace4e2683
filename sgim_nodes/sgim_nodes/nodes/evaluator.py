"""evaluator: measures the learner against the benchmark goals every `eval_every` movements.

It rebuilds the learner's memory from the movement stream (and the demonstrations) and runs
the core Evaluator with its OWN fishing world, so an evaluation never adds a movement, never
touches the learner's memory or simulator, and sees exactly the memory the learner had after
movement N. Evaluations happen at exactly 0, every multiple of `eval_every`, and the run's
budget (`movements`, or, when it is 0, the budget a valid run_status announces). Its memory
holds the valid learner movements and the demonstrations the learner took
(`demonstrations_taken`) shown whole: a demonstration offered but refused never reaches it,
nor does a goal-only or means-only one (the learner stores no pair from it).

Interfaces:
  subscribes  movements, demonstrations_taken, run_status
  publishes   evaluations (sgim_msgs/Evaluation)
Parameters: the common ones, the memory and inverse-model fields of LearnerConfig, eval_every,
movements, noise (of the evaluator's world; default the world's).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from rclpy.node import Node

from sgim_msgs.msg import Demonstration, Evaluation, Movement, RunStatus
from sgim_nodes.bag.rebuild import rebuild_from_records
from sgim_nodes.bag.record_checks import Limits
from sgim_nodes.bag.resume import records_until, resume_point
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.evaluator import EVALUATION_SEED_OFFSET, Evaluator
from sgim_nodes.core.inverse_model import InverseModel
from sgim_nodes.core.learners import inverse_model_for, inverse_or_centre
from sgim_nodes.nodes.movement_memory import MOVEMENTS, MovementMemory
from sgim_nodes.nodes.ros_glue import (
    declare_learner,
    floats,
    learner_node_params,
    vec,
    world_scale,
)
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import declared, publishes, serves, subscribes
from sgim_ros.params import Param, non_negative
from sgim_ros.ready import serve_ready
from sim_bridge.data_files import load_benchmark_goals
from sim_bridge.fishing_world import DEFAULT_NOISE, FishingWorld

PARAMS = learner_node_params(
    Param("eval_every", 250, "movements between evaluations (paper: 250); 0 = only at the "
          "start and the end", non_negative),
    Param("noise", DEFAULT_NOISE, "motor-command noise of the evaluator's own world",
          non_negative),
    Param("movements", 0, "the run's movement budget, evaluated at its end (0: take it from "
          "the run status)", non_negative),
)

EVALUATIONS, READY = publishes("evaluations"), serves("evaluator_ready")
TAKEN, STATUS = subscribes("demonstrations_taken"), subscribes("run_status")
INTERFACES = declared(EVALUATIONS, READY, TAKEN, STATUS, MOVEMENTS)


class EvaluatorNode(Node):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("evaluator", **node_options)
        values, config = declare_learner(self, PARAMS)
        self.every = values["eval_every"]
        self.action_size = values["action_size"]
        goals = load_benchmark_goals()
        self.world = FishingWorld(seed=values["seed"] + EVALUATION_SEED_OFFSET,
                                  noise=values["noise"])
        scale = world_scale(values)
        self.evaluator = Evaluator(self.world, goals, scale.diagonal)
        self.memory = MovementMemory(self, config, self.action_size, values["outcome_size"],
                                     scale)
        self.memory.before_store.append(self._before_movement)
        self.memory.after_store.append(self._after_movement)
        self.final: int | None = values["movements"] or None
        self.gate = LiveGate(self.get_logger().error, Limits(
            self.action_size, values["outcome_size"], budget=values["movements"]))
        self.done: set[int] = set()
        self.missed: list[int] = []
        if values["resume_from"]:
            point = resume_point(values["resume_from"], config,
                                 values["resume_segments"])
            self.memory.resume(point)
            self.done = set(point.evaluated)
            # Evaluations the interruption cut short are done again on the memory of their
            # time, rebuilt from the recordings, once the resumed run starts.
            self.missed = [k for k in range(0, point.count + 1, self.every or point.count + 1)
                           if k not in self.done]
            self.done |= {0}
            self._point, self._config = point, config
        self._out = EVALUATIONS.create(self)
        # The arbiter starts once these have matched (a missed movement would stall the
        # evaluations: sgim_ros/ready.py).
        serve_ready(self, READY, {
            "movements": self.memory.subscription,
            "demonstrations_taken": TAKEN.create(self, self._on_demo),
            "run_status": STATUS.create(self, self._on_status)})
        self.get_logger().info(f"{len(goals)} benchmark goals, every {self.every} movements")

    def _on_demo(self, msg: Demonstration) -> None:
        if self.gate.check("demonstrations_taken", msg):
            return
        if len(msg.action) and len(msg.outcome):  # goal- or means-only: not in memory
            self.memory.add_demonstration_after(msg.movement_index, vec(msg.action),
                                                vec(msg.outcome))

    def _on_status(self, msg: RunStatus) -> None:
        if self.gate.check("run_status", msg):  # a forged status moves no evaluation
            return
        if 0 not in self.done:
            self._evaluate(0)
        while self.missed:
            k = self.missed.pop(0)
            state = rebuild_from_records(records_until(self._point.records, k), self._config)
            self.done.discard(k)
            self._evaluate(k, inverse_model_for(state.memory, self._config,
                                                    self.memory.scale))
        if self.final is None and msg.movement_index == msg.total_movements:
            self.final = msg.total_movements
        if self.final is not None and self.memory.count >= self.final:
            self._evaluate(self.final)

    def _before_movement(self, msg: Movement) -> None:
        if 0 not in self.done:
            self._evaluate(0)

    def _after_movement(self, msg: Movement) -> None:
        n = msg.index
        if (self.every and n % self.every == 0) or n == self.final:
            self._evaluate(n)

    def _evaluate(self, count: int, model: InverseModel | None = None) -> None:
        if count in self.done:
            return
        self.done.add(count)
        start = time.perf_counter()
        model = model or self.memory.inverse_model
        result = self.evaluator.evaluate(
            lambda goal: inverse_or_centre(model, goal, self.action_size))
        goals = self.evaluator.goals
        self._out.publish(Evaluation(
            stamp=self.get_clock().now().to_msg(), movement_index=count,
            mean_distance=result.mean_distance, outcome_size=goals.shape[1],
            goals=floats(goals), reached=floats(result.reached),
            distances=floats(result.distances)))
        casts = self.evaluator.casts
        self.get_logger().info(f"evaluation at {count}: mean distance "
                               f"{result.mean_distance:.4f} ({int(np.sum(result.failed))} "
                               f"failed, {time.perf_counter() - start:.1f} s; casts made "
                               f"{casts.made}, kept {casts.saved} in all)")

    def destroy_node(self) -> None:
        self.world.close()
        super().destroy_node()


ENTRY = NodeEntry(EvaluatorNode)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
