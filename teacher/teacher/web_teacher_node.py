"""ROS 2 node `web_teacher`: a person teaches a run from a live page in a browser.

It takes the automatic teacher's place (`run_experiment.sh sgim-d --teacher web`) and serves,
on 127.0.0.1 by default, a page that draws the run as it goes (landings coloured by process,
the interest tree's leaves coloured by interest, the teaching goals reached or not, the
current goal, the error curve, the count and the budget) and lets the person demonstrate a
teaching goal, accept the library's most reliable action for any point, paste 24 numbers,
and pause, resume or step the run (counted where the run stands: web/pacing.py). The
decisions are the terminal teacher's (human_commands), the picture the markers node's
(sgim_nodes.view.picture).

Threads: the HTTP server answers in its own threads, reading the picture under one lock;
whatever touches ROS (publishing, service calls) is queued to the main thread, which spins
the node (a 50 Hz timer takes the queue) and answers each queued command when it is done.
The cast of the latest demonstration is drawn in a low-priority child process, so the run is
not slowed (web/cast_pictures.py).

After the run: with `linger` > 0 and a page open (it asked for the state in the last 90 s),
the page keeps being served, saying the run is over, until the person closes it there or
`linger` seconds pass. The launcher waits for that (graph/experiment.py), by two files beside
`address_file`: the address file is removed once the node heard the end of the run (at once
when it does not linger), and `web_teacher.linger` exists while it lingers. Once the node's
ROS context is shut down, every request about the run is answered 503 "the run is over"
until the server stops (web/server.py).

Interfaces:
  topics    movements, region_map, goals, evaluations, demonstrations, run_status,
            pace_state (subscribed); demonstrations (published, source "web")
  clients   execute_action (measures a pasted action, record=false), pace (the arbiter's)
Parameters: host, port, token, address_file, tolerance_noise, outcome_noise, teaching_set,
execute_timeout, render_casts, linger (see PARAMS).
"""

from __future__ import annotations

import math
import queue
import time
import zipfile
from concurrent.futures import Future as ThreadFuture
from concurrent.futures import TimeoutError as ThreadTimeout
from pathlib import Path
from typing import Any

import numpy as np
from rclpy.node import Node
from rclpy.task import Future

from sgim_msgs.msg import Demonstration, Movement, PaceState, RunStatus
from sgim_msgs.srv import ExecuteAction, Pace
from sgim_nodes.nodes.picture_feed import (
    PICTURE_INTERFACES,
    REACH_PARAMS,
    follow,
    reach_tolerance,
)
from sgim_nodes.view.picture import LivePicture
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import calls, declared, publishes, serves, subscribes
from sgim_ros.params import Param, ParameterError, declare, non_negative, positive
from sgim_ros.ready import serve_ready
from sim_bridge.data_files import load_teaching_set
from sim_bridge.data_params import TEACHING_SET_FILE
from teacher.human_commands import CommandError, NoneThere, PaceRequest
from teacher.human_decisions import (
    ExecuteFirst,
    LearnerState,
    SendDemonstration,
    TeachingLibrary,
    executed_demonstration,
)
from teacher.web.app import WebTeacher
from teacher.web.cast_pictures import CastRenderer, lake_png
from teacher.web.pacing import SETTLE, PacePlan, PaceReply, Request
from teacher.web.server import RUN_OVER, Api, Refused, RunOver, serve
from teacher.web_expert import WEB_EXPERT, WEB_EXPERT_INTERFACES, WebExpert

PARAMS = (
    Param("host", "127.0.0.1", "interface to serve the page on; another than this machine's "
          "needs a token"),
    Param("port", 8765, "TCP port of the page (0: any free port, see address_file)",
          lambda v: 0 <= v <= 65535, "0 to 65535"),
    Param("token", "", "access token the page's address must carry (?token=); needed on an "
          "interface other than loopback (16 characters at least)"),
    Param("address_file", "", "file to write the page's address into once it serves (for "
          "launchers and tests); empty: none"),
    *REACH_PARAMS,
    Param("teaching_set", "", "teaching-set file (.npz); empty: the packaged one",
          TEACHING_SET_FILE),
    Param("execute_timeout", 30.0, "seconds to wait for execute_action to measure a pasted "
          "action", positive, "> 0"),
    Param("render_casts", True, "draw the latest demonstration's cast as a GIF for the page "
          "(a low-priority child process)"),
    Param("expert", False, "SGIM-ACTS: answer the learner's requests as its teacher 'web' "
          "(teacher/web_expert.py); false: teach SGIM-D or demo-only when the person likes"),
    # Not read-only: how long a finished run's page stays does not shape the run (and is
    # kept out of its fingerprint); it is read when the run ends.
    Param("linger", 0.0, "seconds the page stays after the run while someone looks at it, "
          "unless closed there; 0: it ends with the run", non_negative, read_only=False),
)
PACE_COMMANDS = {"query": Pace.Request.QUERY, "pause": Pace.Request.PAUSE,
                 "resume": Pace.Request.RESUME, "step": Pace.Request.STEP}
COMMAND_WAIT = 10.0  # seconds the page waits for a command that needs no simulator
SERVICE_WAIT = 5.0  # seconds a command waits for its service to be discovered
ANSWER_POLL = 0.2  # seconds between an HTTP thread's looks at whether the run is gone

DEMONSTRATIONS, READY = publishes("demonstrations"), serves("teacher_ready")
STATUS, PACE_STATE = subscribes("run_status"), subscribes("pace_state")
EXECUTE, PACE = calls("execute_action"), calls("pace")
INTERFACES = declared(DEMONSTRATIONS, READY, STATUS, PACE_STATE, EXECUTE, PACE,
                      PICTURE_INTERFACES, WEB_EXPERT_INTERFACES)


class WebTeacherNode(Node, Api):
    def __init__(self, **node_options: Any) -> None:
        """``node_options``: rclpy Node's (a test's context and parameter overrides)."""
        super().__init__("web_teacher", **node_options)
        p = declare(self, PARAMS)
        where = p["teaching_set"] or "the packaged teaching set"
        try:
            teaching = load_teaching_set(p["teaching_set"] or None)
            library = TeachingLibrary(teaching.actions, teaching.outcomes, reach_tolerance(p))
        except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile) as error:
            raise ParameterError(f"parameter 'teaching_set': cannot use {where}: {error}") \
                from None
        self.execute_timeout = p["execute_timeout"]
        self.p = p
        self.app = WebTeacher(library, LivePicture(library.teacher),
                              LearnerState(library.action_size))
        self._queue: queue.Queue[tuple[Any, ThreadFuture]] = queue.Queue()
        self._pending: list[tuple[Future, float, Any, ThreadFuture]] = []
        self._waiting: list[tuple[Any, ThreadFuture, float]] = []  # for their service
        self._later: list[tuple[float, PacePlan, Request, ThreadFuture]] = []  # pace calls
        self._demos = DEMONSTRATIONS.create(self)
        # Movements reach the page only through the picture's checks (signed, in the count).
        followed = follow(self, self.app.picture, self.app.lock, also=self._on_movement)
        # The arbiter starts once these have matched (sgim_ros/ready.py).
        serve_ready(self, READY, {"movements": followed["movements"],
                                  "run_status": STATUS.create(self, self._on_status)})
        PACE_STATE.create(self, self._on_pace)
        self.expert = WebExpert(self, self.app.say) if p["expert"] else None
        self.app.expert = WEB_EXPERT if p["expert"] else ""
        self._execute, self._pace = EXECUTE.create(self), PACE.create(self)
        self._lake = lake_png()
        self.casts = CastRenderer(p["render_casts"], self.get_logger().warning)
        try:
            self.server = serve(p["host"], p["port"], p["token"], self)
        except Refused as error:
            raise ParameterError(str(error)) from None
        self.url = self.server.url
        self.context.on_shutdown(self._context_over)
        self.create_timer(0.02, self.work)  # queued commands, pending calls, the cast
        self.address_file = Path(p["address_file"]) if p["address_file"] else None
        self.linger_file = (self.address_file.with_suffix(".linger")
                            if self.address_file is not None else None)
        self._lingering = False
        if self.address_file is not None:
            self.address_file.write_text(self.url + "\n")
        self.get_logger().info(f"teach at {self.url}")
        self.app.say(f"{len(library.actions)} teaching goals from {where}; reach tolerance "
                     f"{reach_tolerance(p):g}")

    # --- what the graph says -------------------------------------------------------------

    def _on_movement(self, msg: Movement) -> None:
        """A movement the picture's checks admitted (follow)."""
        with self.app.lock:
            problem = self.app.learner.add_movement(
                msg.index, msg.status == Movement.STATUS_OK, msg.action, msg.outcome)
            self.app.movement_seen(int(msg.index), int(msg.process))
        if problem:
            self.get_logger().warning(problem)

    def _on_status(self, msg: RunStatus) -> None:
        with self.app.lock:
            learner = self.app.learner
            learner.total = int(msg.total_movements)
            if msg.state == RunStatus.STATE_FINISHED:
                learner.run_over = "finished"
            elif msg.state == RunStatus.STATE_ABORTED:
                learner.run_over = f"aborted: {msg.message}"
        if msg.message and msg.message not in ("started", ""):
            level = ("warning" if " refused: " in msg.message
                     or msg.state == RunStatus.STATE_ABORTED else "info")
            self.app.say(f"run: {msg.message}", level)
        if msg.state in (RunStatus.STATE_FINISHED, RunStatus.STATE_ABORTED):
            self._run_ended()

    def _run_ended(self) -> None:
        """Linger or not (see the module's docstring), and tell the launcher which."""
        if self.app.linger.decided:
            return
        self._lingering = self.app.run_ended(self.p["linger"])
        if self._lingering:
            self.get_logger().info(f"the run is over: the page stays at {self.url} for at "
                                   f"most {self.p['linger']:g} s, or until closed there")
            if self.linger_file is not None:
                self.linger_file.write_text(self.url + "\n")
        if self.address_file is not None:
            self.address_file.unlink(missing_ok=True)

    def _stop_lingering(self) -> None:
        self._lingering = False
        self.app.say("this page is closing: the web teacher stops", "turn")
        self.get_logger().info("the page was closed, or its time after the run ran out")
        if self.linger_file is not None:
            self.linger_file.unlink(missing_ok=True)

    def _on_pace(self, msg: PaceState) -> None:
        with self.app.lock:
            pace = self.app.pace
            was_waiting, was_held = pace.waiting, pace.paused and pace.held
            pace.known, pace.paused, pace.waiting = True, msg.paused, msg.waiting_for_teacher
            pace.held = msg.held
            pace.steps_left, pace.wait_seconds = msg.steps_left, msg.wait_seconds
            pace.period = msg.teacher_period
            pace.turn_ends = (time.monotonic() + msg.wait_seconds_left
                              if msg.waiting_for_teacher and msg.wait_seconds_left >= 0
                              else math.inf)
        if msg.waiting_for_teacher and not was_waiting:
            self.app.say(f"your turn at movement {msg.movement_index}: demonstrate, or "
                         "resume to go on", "turn")
        elif msg.paused and msg.held and not was_held and not self._planning():
            # held: the arbiter's count is where the run stands (its "pausing" text is older)
            self.app.say(msg.message if msg.message.startswith(("step done", "paused")) else
                         f"paused at movement {msg.movement_index}")

    def _planning(self) -> bool:
        """Whether a page's pace command is under way (its answer says where the run is)."""
        return bool(self._later) or any(isinstance(item[2], PacePlan) for item in self._pending)

    # --- the server's questions (HTTP threads) --------------------------------------------

    def _context_over(self) -> None:
        """The ROS context is shut down: what the page asks is answered 503 from now on."""
        self.server.over = RUN_OVER

    def _running(self) -> None:
        if not self.context.ok():
            raise RunOver(RUN_OVER)

    def state(self, query: dict[str, int]) -> dict[str, Any]:
        self._running()
        try:
            listeners = self._demos.get_subscription_count()
        except Exception:  # rclpy's RCLError once the context is shut down under us
            self._running()
            raise
        with self.app.lock:
            self.app.learner.listeners = listeners
        return self.app.state(**query)

    def legend(self) -> dict[str, Any]:
        return self.app.legend()

    def image(self, name: str) -> bytes | None:
        return self._lake if name == "lake.png" else self.casts.picture

    def command(self, body: Any) -> dict[str, Any]:
        self._running()
        return self.app.command(body, self._carry_out)

    def _carry_out(self, decision: Any) -> dict[str, Any]:
        """Hand a decision to the main thread (which owns ROS) and wait for its answer."""
        done: ThreadFuture = ThreadFuture()
        self._queue.put((decision, done))
        wait = COMMAND_WAIT + SERVICE_WAIT + (
            self.execute_timeout if isinstance(decision, ExecuteFirst) else
            SETTLE if isinstance(decision, PaceRequest) else 0.0)
        end = time.monotonic() + wait
        while True:  # the main thread stops answering once the run is gone: say so at once
            try:
                return done.result(timeout=max(0.0, min(ANSWER_POLL, end - time.monotonic())))
            except ThreadTimeout:
                self._running()
                if time.monotonic() >= end:
                    return {"ok": False, "message": f"no answer within {wait:g} s: is the "
                            "node busy?"}

    # --- the main thread: commands that touch ROS -------------------------------------------

    def work(self) -> None:
        """Obey queued commands and finish pending calls; called between spin_once calls."""
        while True:
            try:
                decision, done = self._queue.get_nowait()
            except queue.Empty:
                break
            self._waiting.append((decision, done, time.monotonic() + SERVICE_WAIT))
        for item in list(self._waiting):  # a service a client has not matched yet
            decision, done, deadline = item
            if self._ready(decision) or time.monotonic() > deadline:
                self._waiting.remove(item)
                self._start(decision, done)
        for item in list(self._pending):
            future, deadline, decision, done = item
            if future.done() or time.monotonic() > deadline:
                self._pending.remove(item)
                self._finish(future, decision, done)
        for item in list(self._later):  # a pace plan's next call, when it is due
            if time.monotonic() >= item[0]:
                self._later.remove(item)
                self._call_pace(*item[1:])
        self._poll_render()
        if self._lingering and self.app.linger_ended():
            self._stop_lingering()

    def _ready(self, decision: Any) -> bool:
        """Whether the service the decision needs is matched (discovery takes a moment)."""
        if isinstance(decision, ExecuteFirst):
            return self._execute.service_is_ready()
        if isinstance(decision, PaceRequest):
            return self._pace.service_is_ready()
        return True

    def _start(self, decision: Any, done: ThreadFuture) -> None:
        try:
            if isinstance(decision, SendDemonstration):
                done.set_result(self._send(decision))
            elif isinstance(decision, NoneThere):
                done.set_result(self._none_there())
            elif isinstance(decision, ExecuteFirst):
                if not self._execute.service_is_ready():
                    raise CommandError("the simulator's execute_action service is not "
                                       "available to measure the action's outcome")
                future = self._execute.call_async(ExecuteAction.Request(
                    action=[float(v) for v in decision.action],
                    process=Movement.PROCESS_DEMONSTRATION, movement_index=0, record=False))
                self.app.say("executing the pasted action to measure its outcome...")
                self._pending.append((future, time.monotonic() + self.execute_timeout,
                                      decision, done))
            elif isinstance(decision, PaceRequest):
                if not self._pace.service_is_ready():
                    raise CommandError("the run has no pace service (is it running, with a "
                                       "human teacher?)")
                plan = PacePlan(decision.what, decision.steps, time.monotonic())
                self._call_pace(plan, plan.first(), done)
        except CommandError as error:
            self.app.say(f"refused: {error}", "error")
            done.set_result({"ok": False, "message": str(error)})

    def _finish(self, future: Future, decision: Any, done: ThreadFuture) -> None:
        try:
            if not future.done():
                future.cancel()
                raise CommandError("the service did not answer in time")
            reply = future.result()
            if isinstance(decision, PacePlan):
                self._paced(decision, reply, done)
                return
            landed = reply.status == Movement.STATUS_OK and len(reply.outcome) == 2
            demo = executed_demonstration(decision, landed, np.asarray(reply.outcome),
                                          reply.message)
            with self.app.lock:
                why = self.app.learner.refusal()
            if why:
                raise CommandError(why)
            done.set_result(self._send(demo))
        except CommandError as error:
            self.app.say(f"refused: {error}", "error")
            done.set_result({"ok": False, "message": str(error)})

    def _call_pace(self, plan: PacePlan, request: Request, done: ThreadFuture) -> None:
        future = self._pace.call_async(Pace.Request(command=PACE_COMMANDS[request.command],
                                                    steps=request.steps))
        self._pending.append((future, time.monotonic() + COMMAND_WAIT, plan, done))

    def _paced(self, plan: PacePlan, reply: Pace.Response, done: ThreadFuture) -> None:
        """A pace plan's reply: its next call, or the page's answer (web/pacing.py)."""
        state = reply.state
        step = plan.next(PaceReply(bool(reply.accepted), reply.message, state.paused,
                                   state.held, int(state.movement_index),
                                   int(state.total_movements)), time.monotonic())
        if isinstance(step, Request):
            self._later.append((time.monotonic() + step.after, plan, step, done))
            return
        self.app.say(step["message"], "info" if step["ok"] else "error")
        done.set_result(step)

    def _send(self, demo: SendDemonstration) -> dict[str, Any]:
        with self.app.lock:
            learner = self.app.learner
            why = learner.refusal()
            if why:
                raise CommandError(why)
            if self._demos.get_subscription_count() == 0:
                raise CommandError("nobody subscribes to 'demonstrations' (is the learner "
                                   "running?): nothing sent")
            stamp = self.get_clock().now().to_msg()
            msg = (None if self.expert is None else  # the oldest request's answer
                   self.expert.answer(stamp, learner.demonstrations + 1, demo.action,
                                      demo.outcome, demo.teaching_set_index))
            learner.demonstrations += 1
            number = learner.demonstrations
            at = learner.movement_count if msg is None else msg.movement_index
            self.app.demonstration_sent(number, at)
        self._demos.publish(msg or Demonstration(
            stamp=stamp, index=number, movement_index=at,
            action=[float(v) for v in demo.action], outcome=[float(v) for v in demo.outcome],
            teaching_set_index=demo.teaching_set_index, source="web"))
        text = f"sent demonstration {number} at movement {at}: {demo.text}"
        if msg is not None:
            text += f" ({self.expert.describe(msg)})"
        self.app.say(text, "sent")
        self.casts.queue(demo.action, f"demonstration {number}: {demo.text}")
        return {"ok": True, "message": text, "demonstration": number, "movement": at}

    def _none_there(self) -> dict[str, Any]:
        if self.expert is None:
            raise CommandError("nobody asked: 'none there' answers SGIM-ACTS's requests, and "
                               "this run's learner teaches itself from what you show")
        msg = self.expert.none_there(self.get_clock().now().to_msg())
        self._demos.publish(msg)
        text = self.expert.describe(msg)
        self.app.say(text, "sent")
        return {"ok": True, "message": text}

    def _poll_render(self) -> None:
        finished, busy = self.casts.poll()
        if finished is not None or busy != self.app.cast["rendering"]:
            with self.app.lock:
                self.app.cast["rendering"] = busy
                if finished is not None:
                    self.app.cast["version"] += 1
                    self.app.cast["caption"] = finished

    def destroy_node(self) -> None:
        self.server.stop()
        for file in (self.address_file, self.linger_file):  # it serves no more
            if file is not None:
                file.unlink(missing_ok=True)
        self.casts.stop()
        super().destroy_node()


ENTRY = NodeEntry(WebTeacherNode)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
