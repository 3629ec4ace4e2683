"""Pace control of a run with a human teacher: pause, resume, step, and teacher turns.

A person cannot follow 50 movements per second. The arbiter (social_interaction) owns one
``PaceControl`` when its teacher is human; both human teachers (the web page and the terminal
prompt) drive it through one service, so the rules live here once:

- ``pause`` stops the run before its next movement: a goal attempt under way is cut at its
  next movement boundary (the arbiter cancels it, as for a demonstration), an imitation is
  never split;
- ``resume`` goes on; ``step N`` makes N movements, then pauses again;
- with ``wait_for_teacher`` != 0, the run stops at every ``demonstration_period``-th movement
  (the automatic teacher's boundaries, the first one before any movement) and waits for the
  human: a demonstration or ``resume`` ends the turn, so does the end of ``wait_for_teacher``
  seconds (< 0: no end). Time spent paused does not count against the turn.

Interfaces (relative names):
  service   pace        (sgim_msgs/srv/Pace): QUERY, PAUSE, RESUME, STEP -> accepted, message,
                        state
  publishes pace_state  (sgim_msgs/msg/PaceState, LATEST_STATE) at every change
Without a human teacher nothing here is created and the run is never held.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from rclpy.node import Node
from rclpy.task import Future

from sgim_msgs.msg import PaceState
from sgim_msgs.srv import Pace
from sgim_ros.entry import first_of
from sgim_ros.interfaces import publishes, serves

FOREVER = -1.0  # wait_for_teacher: wait until the teacher acts


HUMAN_TURNS = "a social run whose teacher is a person (human, web or external)"
PACE_INTERFACES = (publishes("pace_state", HUMAN_TURNS), serves("pace", HUMAN_TURNS))


class PaceControl:
    def __init__(self, node: Node, total: int, period: int, wait_seconds: float,
                 preempt: Callable[[], None]) -> None:
        """``period``: movements between teacher turns; ``wait_seconds``: 0 no turns, < 0
        forever; ``preempt``: cuts a running goal attempt at its next movement boundary."""
        self.node = node
        self.total = total
        self.wait_seconds = float(wait_seconds)
        self.period = period if self.wait_seconds != 0 else 0
        self.preempt = preempt
        self.count = 0
        self.paused = False
        self.held = False  # standing still now, in hold() or at a teacher turn
        self._step_done = False
        self.steps_left = 0
        self.waiting = False
        self.turn_ended = False
        self.turn_deadline = math.inf
        self.message = ""
        self._changes: list[Future] = []
        state, service = PACE_INTERFACES
        self._publisher = state.create(node)
        service.create(node, self._serve)
        self.publish("ready")

    # --- the arbiter's side ------------------------------------------------------------

    def turn_due(self, count: int) -> bool:
        return bool(self.period) and count % self.period == 0 and count < self.total

    def cap(self, movements: int) -> int:
        """At most the movements a step still allows, and never past a teacher turn."""
        if self.steps_left:
            movements = min(movements, self.steps_left)
        if self.period:
            movements = min(movements, self.period - self.count % self.period)
        return max(1, movements)

    def moved(self, count: int) -> None:
        """The arbiter's count after a job; ends a step when its movements are made."""
        made, self.count = count - self.count, count
        if self.steps_left:
            self.steps_left = max(0, self.steps_left - made)
            if not self.steps_left:
                self.paused, self._step_done = True, True

    async def hold(self, count: int) -> None:
        """Return once the run is not paused; ``count``: the arbiter's, before its next job."""
        self.count = count
        if not self.paused:
            return
        self.held = True
        done, self._step_done = self._step_done, False
        self.publish(f"{'step done: ' if done else ''}paused at movement {count}")
        try:
            while self.paused:
                await self._change()
        finally:
            self.held = False

    async def teacher_turn(self, count: int, demonstration_ready: Callable[[], bool]) -> str:
        """Wait at a teacher turn; returns how it ended, for the log."""
        self.count = count
        self.waiting, self.turn_ended, self.held = True, False, True
        limited = self.wait_seconds > 0
        self.turn_deadline = time.monotonic() + self.wait_seconds if limited else math.inf
        self.publish(f"teacher's turn at movement {count}")
        try:
            while True:
                if demonstration_ready():
                    return "a demonstration"
                if self.turn_ended:
                    return "the teacher went on"
                if self.paused:  # paused time does not count against the turn
                    started = time.monotonic()
                    await self._change()
                    self.turn_deadline += time.monotonic() - started
                    continue
                left = self.turn_deadline - time.monotonic()
                if left <= 0:
                    return f"no demonstration within {self.wait_seconds:g} s"
                await first_of(self.node, self._change_future(), min(left, 3600.0))
        finally:
            self.waiting = self.held = False
            self.publish(f"teacher's turn at movement {count} over")

    def notify(self) -> None:
        """Something the arbiter waits on may have changed (a demonstration came)."""
        changes, self._changes = self._changes, []
        for future in changes:
            if not future.done():
                future.set_result(True)

    # --- the teachers' side --------------------------------------------------------------

    def _serve(self, request: Pace.Request, response: Pace.Response) -> Pace.Response:
        response.accepted, response.message = self.obey(request.command, request.steps)
        response.state = self.state()
        return response

    def obey(self, command: int, steps: int = 0) -> tuple[bool, str]:
        if command == Pace.Request.QUERY:
            return True, self.describe()
        if self.count >= self.total:
            return False, f"the movement budget is spent ({self.count}/{self.total})"
        if command == Pace.Request.PAUSE:
            if self.paused:
                return True, f"already paused at movement {self.count}"
            self.paused, self.steps_left = True, 0
            self.preempt()
            message = f"pausing at movement {self.count}"
        elif command == Pace.Request.RESUME:
            self.paused, self.steps_left = False, 0
            self.turn_ended = self.waiting
            message = "going on without a demonstration" if self.waiting else "resumed"
        elif command == Pace.Request.STEP:
            if steps < 1:
                return False, f"a step needs at least 1 movement, got {steps}"
            self.paused, self.steps_left = False, int(steps)
            self.turn_ended = self.waiting
            message = f"stepping {steps} movement{'s' if steps > 1 else ''}"
        else:
            return False, f"unknown pace command {command}"
        self.publish(message)
        self.notify()
        return True, message

    def describe(self) -> str:
        if self.count >= self.total:
            return f"budget spent ({self.count}/{self.total})"
        if self.paused:
            return f"{'paused' if self.held else 'pausing'} at movement {self.count}"
        if self.waiting:
            return f"waiting for the teacher at movement {self.count}"
        if self.steps_left:
            return f"stepping: {self.steps_left} movements left"
        return "running"

    def state(self) -> PaceState:
        left = self.turn_deadline - time.monotonic() if self.waiting else 0.0
        return PaceState(
            stamp=self.node.get_clock().now().to_msg(), movement_index=self.count,
            total_movements=self.total, paused=self.paused, held=self.held,
            steps_left=self.steps_left,
            waiting_for_teacher=self.waiting, wait_seconds=self.wait_seconds,
            wait_seconds_left=max(0.0, left) if math.isfinite(left) else -1.0,
            teacher_period=self.period, message=self.message)

    def publish(self, message: str) -> None:
        self.message = message
        self._publisher.publish(self.state())

    def _change_future(self) -> Future:
        future = Future(executor=self.node.executor)
        self._changes.append(future)
        return future

    async def _change(self) -> None:
        await self._change_future()
