"""ROS 2 node `human_input`: a person at a terminal takes the automatic teacher's place.

The command language lives in ``human_commands`` and every decision in ``human_decisions``
(no ROS); this node feeds them what the graph says and sends what they decide. The terminal
loop and its threads are in ``prompt_loop``.

Two threads, each with one job: the main thread reads lines with ``input()`` (with readline's
line editing and history when stdin is a terminal; history in ~/.sgim_teacher_history), and
a second thread spins the node (``spin_once`` in a loop; EventsExecutor hung in tests here).
One lock keeps them from touching the node's state at once. What the graph says while the
person types (the teacher's turn, a pause, a refused demonstration, progress every 10 %, the
end of the run) is printed above the prompt, which is redrawn with what was being typed; a
new evaluation redraws the prompt in place, so that the error it shows is the latest. When
the run is over the prompt says so and leaves by itself: the reading thread is woken with
SIGINT (rclpy's own signal handlers are not installed, so Ctrl-C is a plain
KeyboardInterrupt). A pipe works the same way as a terminal (tests), without readline: its
lines come through a queue (PipeLines), so that no SIGINT is lost to a blocked read().

Interfaces:
  topic    movements       (sgim_msgs/msg/Movement, RECORDS): reached outcomes, movement count
  topic    evaluations     (sgim_msgs/msg/Evaluation, RECORDS): latest evaluation error
  topic    run_status      (sgim_msgs/msg/RunStatus, RECORDS): budget, the end of the run
  topic    pace_state      (sgim_msgs/msg/PaceState, LATEST_STATE): pause, the teacher's turn
  topic    demonstrations  (sgim_msgs/msg/Demonstration, RECORDS): published, source "human"
  client   execute_action  (sgim_msgs/srv/ExecuteAction): measures a YAML file's action, with
                           record=false so the learner's history is untouched
  client   pace            (sgim_msgs/srv/Pace): pause, resume, step
Parameters: tolerance_noise, outcome_noise (the automatic teacher's "reached"), teaching_set,
execute_timeout (see PARAMS).
"""

from __future__ import annotations

import signal
import sys
import threading
import time
import zipfile
from typing import TextIO

import numpy as np
import rclpy
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

from sgim_msgs.msg import Demonstration, Evaluation, Movement, PaceState, RunStatus
from sgim_msgs.srv import ExecuteAction, Pace
from sgim_nodes.bag.record_checks import Limits
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.nodes.picture_feed import REACH_PARAMS, reach_tolerance
from sgim_ros.interfaces import calls, declared, publishes, serves, subscribes
from sgim_ros.params import Param, ParameterError, declare, positive
from sgim_ros.ready import serve_ready
from sim_bridge.data_files import load_teaching_set
from sim_bridge.data_params import TEACHING_SET_FILE
from teacher.human_commands import (
    OUTCOME_SIZE,
    CommandError,
    GoalPoint,
    PaceRequest,
    Quit,
    Send,
    parse,
)
from teacher.human_decisions import (
    ExecuteFirst,
    LearnerState,
    Reply,
    SendDemonstration,
    TeachingLibrary,
    executed_demonstration,
    prompt,
    unexecuted_demonstration,
)
from teacher.prompt_loop import PipeLines, run, setup_readline

PARAMS = (
    *REACH_PARAMS,
    Param("teaching_set", "",
          "path of a teaching-set .npz (actions, outcomes, spread); empty: the packaged set",
          TEACHING_SET_FILE),
    Param("execute_timeout", 30.0,
          "seconds to wait for execute_action to measure the outcome of a YAML action",
          positive, "> 0"),
)
PACE_COMMANDS = {"pause": Pace.Request.PAUSE, "resume": Pace.Request.RESUME,
                 "step": Pace.Request.STEP}

DEMONSTRATIONS, READY = publishes("demonstrations"), serves("teacher_ready")
MOVEMENTS, EVALUATIONS = subscribes("movements"), subscribes("evaluations")
STATUS, PACE_STATE = subscribes("run_status"), subscribes("pace_state")
EXECUTE, PACE = calls("execute_action"), calls("pace")
INTERFACES = declared(DEMONSTRATIONS, READY, MOVEMENTS, EVALUATIONS, STATUS, PACE_STATE,
                      EXECUTE, PACE)


class HumanInputNode(Node):
    def __init__(self, out: TextIO = sys.stdout, echo: bool = False,
                 interactive: bool = False) -> None:
        super().__init__("human_input")
        p = declare(self, PARAMS)
        where = p["teaching_set"] or "the packaged teaching set"
        try:
            teaching = load_teaching_set(p["teaching_set"] or None)
            self.library = TeachingLibrary(teaching.actions, teaching.outcomes,
                                           reach_tolerance(p))
        except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile) as error:
            raise ParameterError(f"parameter 'teaching_set': cannot use {where}: {error}") \
                from None
        self.execute_timeout = p["execute_timeout"]
        self.state = LearnerState(self.library.action_size)
        self.out, self.echo, self.interactive = out, echo, interactive
        self.lock = threading.RLock()  # the reading thread and the spinning thread
        self.finished = False
        self.at_prompt = False  # the prompt is on screen, waiting for a line
        self._pending: tuple[ExecuteFirst, Future, float] | None = None  # request, future, end
        self._pace_call: Future | None = None
        self._decile = 0  # progress printed every 10 % of the budget
        self._waiting_turn = False
        self._held = False
        self.offer: SendDemonstration | None = None  # made by 'goal X Y', sent by 'send'
        # A rogue movement must not move the count the teacher's demonstrations carry; the
        # first valid movement sets it (a resumed run does not start at 1).
        self.gate = LiveGate(self.get_logger().warning,
                             Limits(self.library.action_size, OUTCOME_SIZE))
        self.gate.movements.resync()
        self._demos = DEMONSTRATIONS.create(self)
        # The arbiter starts once this has matched (sgim_ros/ready.py).
        serve_ready(self, READY, {"movements": MOVEMENTS.create(
            self, self._locked(self._on_movement))})
        EVALUATIONS.create(self, self._locked(self._on_evaluation))
        STATUS.create(self, self._locked(self._on_status))
        PACE_STATE.create(self, self._locked(self._on_pace))
        self._execute, self._pace = EXECUTE.create(self), PACE.create(self)
        self.say(f"human teacher: {len(self.library.actions)} teaching-set entries from "
                 f"{where}, reach tolerance {self.library.teacher.tolerance:g}; type 'help' "
                 "for the commands")

    def _locked(self, callback):
        def locked(msg) -> None:
            with self.lock:
                callback(msg)
        return locked

    # --- what the graph says -----------------------------------------------------------

    def _on_movement(self, msg: Movement) -> None:
        if msg.process == Movement.PROCESS_EVALUATION:
            return
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
            self.redraw()  # the prompt on screen showed the one before

    def _on_status(self, msg: RunStatus) -> None:
        state = self.state
        state.total = int(msg.total_movements)
        state.movement_count = max(state.movement_count, int(msg.movement_index))
        if msg.state == RunStatus.STATE_FINISHED:
            state.run_over = "finished"
        elif msg.state == RunStatus.STATE_ABORTED:
            state.run_over = f"aborted: {msg.message}"
        if state.run_over:
            error = "" if state.evaluation is None else (
                f", final error {state.evaluation[1]:.4f}")
            self.notify(f"the run is over ({state.run_over}) at movement "
                        f"{state.movement_count}{error}: bye")
            self.finished = True
            return
        if " refused: " in msg.message:  # the arbiter did not take a demonstration
            self.notify(f"warning: {msg.message}")
        decile = 10 * state.movement_count // max(1, state.total)
        if decile > self._decile:
            self._decile = decile
            self.notify(f"progress: movement {state.movement_count}/{state.total} "
                        f"({10 * decile} %)")

    def _on_pace(self, msg: PaceState) -> None:
        if msg.waiting_for_teacher and not self._waiting_turn:
            limit = ("no time limit" if msg.wait_seconds < 0
                     else f"{msg.wait_seconds_left:.0f} s")
            self.notify(f"your turn at movement {msg.movement_index} ({limit}): teach N, "
                        "goal X Y then send, or yaml FILE to demonstrate, resume to go on")
        self._waiting_turn = msg.waiting_for_teacher
        held = msg.paused and msg.held
        if held and not self._held:  # the pause took effect (a state, not every message)
            self.notify(msg.message)
        self._held = held

    # --- the terminal ----------------------------------------------------------------------

    @property
    def busy(self) -> bool:
        return self._pending is not None or self._pace_call is not None

    def say(self, text: str, end: str = "\n") -> None:
        self.out.write(text + end)
        self.out.flush()

    def notify(self, text: str) -> None:
        """A line from the graph, printed above the prompt (redrawn with the typed text)."""
        if not self.at_prompt:
            self.say(text)
            return
        if self.interactive:
            import readline

            typed = readline.get_line_buffer()
            self.say(f"\r\x1b[K{text}\n{prompt(self.state)}{typed}", end="")
        else:
            self.say(f"\n{text}")

    def redraw(self) -> None:
        """Draw the prompt again, with what is being typed, so that its numbers are the
        latest: drawn once per line, it showed the evaluation of when it was drawn until the
        person typed (the error stayed at the first one all run). Only on a terminal: a pipe
        gets a prompt per line read."""
        if not (self.at_prompt and self.interactive):
            return
        import readline

        typed = readline.get_line_buffer()
        self.say(f"\r\x1b[K{prompt(self.state)}{typed}", end="")

    def prompt_text(self) -> str:
        return prompt(self.state)

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
        elif isinstance(decision, SendDemonstration) and isinstance(command, GoalPoint):
            self.offer = decision  # an action chosen for the person: they confirm it
            self.say(f"offer: {decision.text}\ntype 'send' to demonstrate it")
        elif isinstance(decision, SendDemonstration):
            self._send(decision)
        elif isinstance(decision, Send):
            if self.offer is None:
                raise CommandError("no offer to send: 'goal X Y' makes one")
            offer, self.offer = self.offer, None
            self._send(offer)
        elif isinstance(decision, ExecuteFirst):
            self._start_execution(decision)
        elif isinstance(decision, PaceRequest):
            self._start_pace(decision)

    def _send(self, demo: SendDemonstration) -> None:
        why = self.state.refusal()
        if why:
            raise CommandError(why)
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

    def _start_pace(self, request: PaceRequest) -> None:
        # Discovery of a service takes a moment after the run starts: give it a few seconds.
        if not self._pace.service_is_ready() and not self._pace.wait_for_service(5.0):
            raise CommandError("the run has no pace service (is the learner running, with "
                               "teacher: human?)")
        self._pace_call = self._pace.call_async(Pace.Request(
            command=PACE_COMMANDS[request.what], steps=request.steps))
        self._pace_deadline = time.monotonic() + 10.0

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
        """Finish a pending call once it answered or timed out (spinning thread)."""
        with self.lock:
            self._poll_pace()
            self._poll_execution()

    def _poll_pace(self) -> None:
        future = self._pace_call
        if future is None or (not future.done() and time.monotonic() < self._pace_deadline):
            return
        self._pace_call = None
        if not future.done():
            future.cancel()
            self._pace.remove_pending_request(future)
            self.say("error: the pace service did not answer within 10 s")
            return
        reply = future.result()
        self.say(reply.message if reply.accepted else f"error: {reply.message}")

    def _poll_execution(self) -> None:
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


def _interrupt(*_: object) -> None:
    raise KeyboardInterrupt


def main(args: list[str] | None = None) -> int:
    # Our own Ctrl-C: a KeyboardInterrupt in the reading thread, not rclpy's shutdown.
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    # Ctrl-C is how the person leaves: Python leaves SIGINT ignored when the process started
    # with it ignored (a background job of a script), so install it whatever we inherited.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _interrupt)  # the launcher's stop: the same clean goodbye
    interactive = sys.stdin.isatty()
    try:
        node = HumanInputNode(echo=not interactive, interactive=interactive)
    except (ParameterError, ParameterException) as error:
        print(f"human_input: {error}", file=sys.stderr)
        rclpy.try_shutdown()
        return 2
    if interactive:
        setup_readline()
    try:
        run(node, input if interactive else PipeLines(sys.stdin, sys.stdout).input)
    except KeyboardInterrupt:
        if not node.finished:  # else the spinner's wake-up came late: all was said
            node.say("\ninterrupted: bye")
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
