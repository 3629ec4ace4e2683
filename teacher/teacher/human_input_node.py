"""ROS 2 node `human_input`: a person at a terminal takes the automatic teacher's place.

The command language and every decision live in ``human_commands`` (no ROS); this node feeds
it what the graph says and sends what it decides. One thread does everything: a ``spin_once``
loop that also polls stdin with ``select``. Why not a reader thread: a daemon thread blocked
in a read of stdin can abort the interpreter at exit, and a second thread touching the node
state would need locks; why not EventsExecutor in the background: it hung in tests here.
Reading the raw file descriptor works the same for a terminal and a pipe (tests), and the
loop ends cleanly at ``quit``, end of input, Ctrl-C or a ROS shutdown.

Interfaces:
  topic    movements       (sgim_msgs/msg/Movement, RECORDS): reached outcomes, movement count
  topic    evaluations     (sgim_msgs/msg/Evaluation, RECORDS): latest evaluation error
  topic    demonstrations  (sgim_msgs/msg/Demonstration, RECORDS): published, source "human"
  client   execute_action  (sgim_msgs/srv/ExecuteAction): measures a YAML file's action, with
                           record=false so the learner's history is untouched
Parameters: tolerance, teaching_set, execute_timeout (see PARAMS).
"""

from __future__ import annotations

import os
import select
import sys
import time
import zipfile
from typing import TextIO

import numpy as np
import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.task import Future

from sgim_msgs.msg import Demonstration, Evaluation, Movement
from sgim_msgs.srv import ExecuteAction
from sgim_nodes.bag.validation import Limits, LiveGate
from sgim_ros import qos
from sgim_ros.params import Param, ParameterError, declare, non_negative, positive
from sim_bridge.data_files import load_teaching_set
from teacher.human_commands import (
    DEFAULT_TOLERANCE,
    OUTCOME_SIZE,
    CommandError,
    ExecuteFirst,
    LearnerState,
    Quit,
    Reply,
    SendDemonstration,
    TeachingLibrary,
    executed_demonstration,
    parse,
    prompt,
    unexecuted_demonstration,
)

PARAMS = (
    Param("tolerance", DEFAULT_TOLERANCE,
          "distance (outcome units) under which a teaching goal counts as reached; the "
          "automatic teacher's default", non_negative, ">= 0"),
    Param("teaching_set", "",
          "path of a teaching-set .npz (actions, outcomes, spread); empty: the packaged set"),
    Param("execute_timeout", 30.0,
          "seconds to wait for execute_action to measure the outcome of a YAML action",
          positive, "> 0"),
)


class StdinLines:
    """Complete lines typed so far, read without blocking from a file descriptor."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.buffer = b""
        self.eof = False

    def poll(self) -> list[str]:
        lines: list[str] = []
        while not self.eof and select.select([self.fd], [], [], 0)[0]:
            chunk = os.read(self.fd, 4096)
            if not chunk:
                self.eof = True
                break
            self.buffer += chunk
        *complete, self.buffer = self.buffer.split(b"\n")
        if self.eof and self.buffer:  # a last line without newline
            complete, self.buffer = [*complete, self.buffer], b""
        lines += [c.decode(errors="replace") for c in complete]
        return lines


class HumanInputNode(Node):
    def __init__(self, out: TextIO = sys.stdout, echo: bool = False) -> None:
        super().__init__("human_input")
        p = declare(self, PARAMS)
        where = p["teaching_set"] or "the packaged teaching set"
        try:
            teaching = load_teaching_set(p["teaching_set"] or None)
            self.library = TeachingLibrary(teaching.actions, teaching.outcomes, p["tolerance"])
        except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile) as error:
            raise ParameterError(f"parameter 'teaching_set': cannot use {where}: {error}") \
                from None
        self.execute_timeout = p["execute_timeout"]
        self.state = LearnerState(self.library.action_size)
        self.out, self.echo = out, echo
        self.finished = False
        self._pending: tuple[ExecuteFirst, Future, float] | None = None  # request, future, end
        # A rogue movement must not move the count the teacher's demonstrations carry; the
        # first valid movement sets it (a resumed run does not start at 1).
        self.gate = LiveGate(self.get_logger().warning,
                             Limits(self.library.action_size, OUTCOME_SIZE))
        self.gate.movements.resync()
        self._demos = self.create_publisher(Demonstration, "demonstrations", qos.RECORDS)
        self.create_subscription(Movement, "movements", self._on_movement, qos.RECORDS)
        self.create_subscription(Evaluation, "evaluations", self._on_evaluation, qos.RECORDS)
        self._execute = self.create_client(ExecuteAction, "execute_action")
        self.say(f"human teacher: {len(self.library.actions)} teaching-set entries from "
                 f"{where}, reach tolerance {p['tolerance']:g}; type 'help' for the commands")

    # --- what the graph says -----------------------------------------------------------

    def _on_movement(self, msg: Movement) -> None:
        if not self.gate.admit_movement(msg).ok:  # the readers' checks (bag/validation.py)
            return
        landed = msg.status == Movement.STATUS_OK
        problem = self.state.add_movement(msg.index, landed, msg.action, msg.outcome)
        if problem:
            self.get_logger().warning(problem)

    def _on_evaluation(self, msg: Evaluation) -> None:
        if self.gate.check("evaluations", msg):
            return
        latest = self.state.evaluation
        if latest is None or msg.movement_index >= latest[0]:
            self.state.evaluation = (int(msg.movement_index), float(msg.mean_distance))

    # --- the terminal ----------------------------------------------------------------------

    @property
    def busy(self) -> bool:
        return self._pending is not None

    def say(self, text: str, end: str = "\n") -> None:
        self.out.write(text + end)
        self.out.flush()

    def show_prompt(self) -> None:
        self.say(prompt(self.state), end="")

    def handle_line(self, line: str) -> None:
        """Obey one typed line; every mistake is printed, none escapes."""
        if self.echo:
            self.say(line)
        try:
            command = parse(line)
            if command is not None:
                self._obey(command)
        except CommandError as error:
            self.say(f"error: {error}")
        if not self.busy and not self.finished:
            self.show_prompt()

    def end_of_input(self) -> None:
        self.say("\nend of input: bye")
        self.finished = True

    def _obey(self, command) -> None:
        self.state.listeners = self._demos.get_subscription_count()
        decision = self.library.decide(command, self.state)
        if isinstance(decision, Quit):
            self.say("bye")
            self.finished = True
        elif isinstance(decision, Reply):
            self.say(decision.text)
        elif isinstance(decision, SendDemonstration):
            self._send(decision)
        elif isinstance(decision, ExecuteFirst):
            self._start_execution(decision)

    def _send(self, demo: SendDemonstration) -> None:
        self.state.listeners = self._demos.get_subscription_count()
        if self.state.listeners == 0:
            raise CommandError("nobody subscribes to 'demonstrations' (is the learner "
                               "running?): nothing sent")
        self.state.demonstrations += 1
        self._demos.publish(Demonstration(
            stamp=self.get_clock().now().to_msg(),
            index=self.state.demonstrations,
            movement_index=self.state.movement_count,
            action=[float(v) for v in demo.action],
            outcome=[float(v) for v in demo.outcome],
            teaching_set_index=demo.teaching_set_index,
            source="human",
        ))
        self.say(f"sent demonstration {self.state.demonstrations} at movement "
                 f"{self.state.movement_count}: {demo.text}")

    def _start_execution(self, request: ExecuteFirst) -> None:
        if not self._execute.service_is_ready():
            self._send(unexecuted_demonstration(request, "execute_action is not available"))
            return
        self.say(f"executing the action of {request.path} to measure its outcome...")
        future = self._execute.call_async(ExecuteAction.Request(
            action=[float(v) for v in request.action],
            process=Movement.PROCESS_DEMONSTRATION,
            movement_index=0,  # not a learner movement: not counted, not recorded
            record=False,
        ))
        self._pending = (request, future, time.monotonic() + self.execute_timeout)

    def poll(self) -> None:
        """Finish a pending execution once it answered or timed out."""
        if self._pending is None:
            return
        request, future, deadline = self._pending
        if not future.done() and time.monotonic() < deadline:
            return
        self._pending = None
        try:
            if not future.done():
                future.cancel()
                self._execute.remove_pending_request(future)
                self._send(unexecuted_demonstration(
                    request, f"execute_action did not answer within {self.execute_timeout:g} s"))
            else:
                r = future.result()
                landed = r.status == Movement.STATUS_OK and len(r.outcome) == 2
                self._send(executed_demonstration(request, landed, np.asarray(r.outcome),
                                                  r.message))
        except CommandError as error:
            self.say(f"error: {error}")
        if not self.finished:
            self.show_prompt()


def run(node: HumanInputNode, fd: int) -> None:
    """One thread: ROS callbacks, the pending service call and typed lines, in turn."""
    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    lines = StdinLines(fd)
    queued: list[str] = []
    node.show_prompt()
    try:
        while not node.finished and node.context.ok():
            executor.spin_once(timeout_sec=0.05)
            node.poll()
            queued += lines.poll()
            while queued and not node.busy and not node.finished:
                node.handle_line(queued.pop(0))
            if lines.eof and not queued and not node.busy and not node.finished:
                node.end_of_input()
    finally:
        executor.remove_node(node)
        executor.shutdown()


def main(args: list[str] | None = None) -> int:
    rclpy.init(args=args)
    try:
        node = HumanInputNode(echo=not sys.stdin.isatty())
    except (ParameterError, ParameterException) as error:
        print(f"human_input: {error}", file=sys.stderr)
        rclpy.try_shutdown()
        return 2
    try:
        run(node, sys.stdin.fileno())
        if not node.finished:
            node.say("\nROS shut down: bye")
    except (KeyboardInterrupt, ExternalShutdownException):
        node.say("\ninterrupted: bye")
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
