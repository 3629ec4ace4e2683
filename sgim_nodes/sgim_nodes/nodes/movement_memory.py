"""The learner's memory fed by the recorded movement stream, with a wait for a movement count.

The explorer and the evaluator each hold a copy of the learner's memory, built from the one
stream every movement goes through (`movements`, in order, nothing dropped). A job that must
see the memory after movement N awaits `reached(N)`: the same memory the single-process
learner would have at that point, whatever the message timing.

Every movement passes the validation every bag reader applies (bag/validation.py): a record
that is malformed, out of bounds, a duplicate or a jump ahead of the run's count is logged
and ignored, so a rogue publisher can neither fill the memory nor move the count; a
re-execution of the latest movement (a higher `attempt`) replaces its first record, as the
readers replace it.
"""

from __future__ import annotations

import numpy as np
from rclpy.node import Node
from rclpy.task import Future

from sgim_msgs.msg import Movement
from sgim_nodes.bag.record_checks import Limits
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.learners import DEMONSTRATION, build_memory
from sgim_nodes.core.memory import Memory
from sgim_nodes.core.scale import WorldScale
from sgim_nodes.nodes.ros_glue import PROCESS_LABELS, check_vector, vec
from sgim_ros.interfaces import subscribes

MOVEMENTS = subscribes("movements")  # in the INTERFACES of each node that keeps a memory


class MovementMemory:
    """Subscribes `movements` on `node`; holds the Memory and InverseModel of the learner."""

    def __init__(self, node: Node, config: LearnerConfig, action_size: int,
                 outcome_size: int, scale: WorldScale, limits: Limits | None = None) -> None:
        self.node = node
        self.config, self.scale = config, scale
        self.action_size, self.outcome_size = action_size, outcome_size
        self.memory, self.inverse_model = build_memory(config, action_size, outcome_size,
                                                       scale)
        self.count = 0  # the run's count: the latest valid learner movement
        self.before_store: list = []  # called with each learner Movement before it is stored
        self.after_store: list = []  # ... and after (then memory holds it)
        self.gate = LiveGate(node.get_logger().error,
                             limits or Limits(action_size, outcome_size))
        self._latest_row: int | None = None  # memory row of movement `count`, if stored
        self._deferred: list[tuple[int, np.ndarray, np.ndarray]] = []
        self._waiters: list[tuple[int, Future]] = []
        self.subscription = MOVEMENTS.create(node, self._on_movement)

    def _on_movement(self, msg: Movement) -> None:
        verdict = self.gate.admit_movement(msg)
        if not verdict.ok:
            return
        if verdict.supersedes:
            self._supersede(msg)
            return
        for listener in self.before_store:
            listener(msg)
        self._store_deferred(before=msg.index)
        self._latest_row = None
        if msg.status == Movement.STATUS_OK:
            self._latest_row = self.memory.add(vec(msg.action), vec(msg.outcome),
                                               PROCESS_LABELS.get(msg.process, ""))
        self.count = msg.index
        for listener in self.after_store:
            listener(msg)
        for needed, future in self._waiters:
            if needed <= self.count and not future.done():
                future.set_result(True)
        self._waiters = [(n, f) for n, f in self._waiters if not f.done()]

    def _supersede(self, msg: Movement) -> None:
        """The simulator client re-executed the latest movement: its new record is the one
        the learner used, in place of the first."""
        self.node.get_logger().warning(
            f"movement {msg.index} re-executed (attempt {msg.attempt}): its new record "
            "replaces the first")
        ok = msg.status == Movement.STATUS_OK
        self._latest_row = replace_latest(
            self.memory, self._latest_row,
            (vec(msg.action), vec(msg.outcome), PROCESS_LABELS.get(msg.process, "")) if ok
            else None)

    def add_demonstration(self, action: np.ndarray, outcome: np.ndarray) -> str:
        """Store a demonstration as the learner's own experience; '' or why it was refused."""
        why = (check_vector(action, self.action_size, "demonstration action", 1.0)
               or check_vector(outcome, self.outcome_size, "demonstration outcome"))
        if not why:
            self.memory.add(vec(action), vec(outcome), DEMONSTRATION)
        return why

    def add_demonstration_after(self, movement_index: int, action: np.ndarray,
                                outcome: np.ndarray) -> None:
        """Store a demonstration given at `movement_index` just before the next movement is
        stored: the learner received it between those two movements, so anything done at
        movement_index itself (an evaluation) must not see it yet. If that next movement is
        already in, it is stored at once."""
        self._deferred.append((movement_index, action, outcome))
        if movement_index < self.count:
            self._store_deferred(before=self.count + 1)

    def _store_deferred(self, before: int) -> None:
        keep = []
        for index, action, outcome in self._deferred:
            if index < before:
                why = self.add_demonstration(action, outcome)
                if why:
                    self.node.get_logger().error(f"demonstration not stored: {why}")
            else:
                keep.append((index, action, outcome))
        self._deferred = keep

    def resume(self, point) -> None:
        """Start from a resumed run's memory and count (a resume.ResumePoint)."""
        old = point.state.memory
        for action, outcome, label in zip(old.actions, old.outcomes, old.labels, strict=True):
            self.memory.add(action, outcome, label)
        self.count = self.gate.movements.count = point.count
        self.node.get_logger().info(f"resumed at movement {self.count} with "
                                    f"{len(self.memory)} pairs in memory")

    def reached(self, count: int) -> Future:
        """A future done once every movement up to `count` is in memory."""
        future = Future(executor=self.node.executor)
        if count <= self.count:
            future.set_result(True)
        else:
            self._waiters.append((count, future))
        return future


def replace_latest(memory: Memory, row: int | None,
                   pair: tuple[np.ndarray, np.ndarray, str] | None) -> int | None:
    """Replace the memory's latest movement (row `row`, None when it was not stored) with
    `pair` (None: a movement without outcome); returns the row of the replacement.

    Only the last row can be replaced: nothing is stored between a movement and its
    re-execution (the client retries before anything else happens). This reaches into
    Memory's arrays because the core has no "replace": a Memory method would be its home.
    """
    if row is not None and row != len(memory) - 1:
        raise ValueError(f"row {row} is not the memory's latest ({len(memory) - 1})")
    if row is None:
        return None if pair is None else memory.add(*pair)
    if pair is None:  # the re-execution failed: the first record's pair goes
        memory._n -= 1
        memory.labels.pop()
        if memory._n_indexed > memory._n:
            memory._rebuild()
        return None
    memory._actions[row], memory._outcomes[row] = pair[0], pair[1]
    memory.labels[row] = pair[2]
    if row < memory._n_indexed:
        memory._rebuild()  # the KD-tree indexed the old outcome
    return row
