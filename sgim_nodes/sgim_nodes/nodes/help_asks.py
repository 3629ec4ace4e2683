"""The arbiter's side of timing on-request (issue 14): when the learner asks for help.

The rule is the core's (core/help_request.py, HelpRequests): the learner asks when its
competence progress over its latest own goal attempts has stalled and it has earned an ask
(one per P movements). The arbiter drives it as the single-process runner does:

- every goal attempt that spent a movement (a drawn goal, or a goal-only demonstration's
  outcome adopted as a goal; never an imitation) tells the rule its competence when it ends;
- a stalled learner that has used every ask earned so far asks at the movement the next one
  is earned (a multiple of P): its goal attempt is capped there (`cap`), and, cut there, it is
  folded only after the question is put, as the runner's learner folds the attempt its ask
  interrupts (``learner.on_teacher_turn`` after ``HelpRequests.asked``);
- the ask is a HelpRequest on `help_requests` about the goal of the latest attempt folded;
  the teacher answers on `demonstrations` with a Demonstration whose `help_request` names it.
"""

from __future__ import annotations

import numpy as np
from rclpy.node import Node

from sgim_msgs.msg import Demonstration, HelpRequest
from sgim_nodes.core.help_request import HelpRequests, budget_for
from sgim_nodes.nodes.ros_glue import floats
from sgim_ros import qos


class HelpAsks:
    """Ask/tell over the core's HelpRequests, with the asks published and answers kept."""

    def __init__(self, node: Node, total: int, period: int) -> None:
        self.node = node
        self.rule = HelpRequests(budget_for(total, period), period)
        self.period = period
        self.last_goal: np.ndarray | None = None  # the latest own goal attempt's
        self._cut: tuple[np.ndarray, float] | None = None  # an attempt the ask interrupts
        self.answers: dict[int, Demonstration] = {}  # answers not yet taken
        self._answered: set[int] = set()
        self._asked_at: dict[int, int] = {}  # ask index -> the count it was made at
        self._out = node.create_publisher(HelpRequest, "help_requests", qos.RECORDS)

    def resume(self, records, count: int) -> None:
        """Asks already made and the window since the last one, from a run's records (the
        competences of own goal attempts: those with a goal index).

        An attempt that ends where the last ask was made went into the window before the ask
        if it ended by itself, after it if the ask cut it (`attempt_ended`); the ask's goal
        tells which, since it is the goal of the latest attempt folded before the ask. One
        case stays open: a run stopped right where an ask was due, before it was made, whose
        last attempt the ask would have cut is folded as if it had ended by itself."""
        asks = [h for h in records.help_requests if h.movement_index < count]
        self.rule.asks = len(asks)
        last = asks[-1] if asks else None
        own = [c for c in records.competences if c.goal_index > 0 and c.movement_index <= count]
        for c in own:
            if last is None or c.movement_index > last.movement_index or (
                    c.movement_index == last.movement_index
                    and not np.allclose(c.goal, last.goal)):  # the attempt the ask cut
                self.rule.attempt_ended(c.competence)
        if own:
            self.last_goal = np.asarray(own[-1].goal, dtype=float)

    def cap(self, count: int, cap: int) -> int:
        """Movements the next goal attempt may make: up to the movement where a stalled learner
        earns its next ask, when it has used every ask earned so far."""
        rule = self.rule
        if rule.stalled() and rule.asks < rule.budget and rule.asks >= rule.allowance(count):
            return min(cap, (count // self.period + 1) * self.period - count)
        return cap

    def attempt_ended(self, goal: np.ndarray, movements_used: int, competence: float,
                      finished: bool, count: int) -> None:
        """A goal attempt's result, at learner count `count` after it."""
        if movements_used == 0:
            return
        if not finished and self.rule.should_ask(count):
            self._cut = (np.asarray(goal, dtype=float), float(competence))  # after the ask
        else:
            self._fold(goal, competence)

    def _fold(self, goal: np.ndarray, competence: float) -> None:
        self.rule.attempt_ended(competence)
        self.last_goal = np.asarray(goal, dtype=float)

    def should_ask(self, count: int) -> bool:
        if self._cut is not None and not self.rule.should_ask(count):
            self._fold(*self._cut)  # not an ask's cut (the budget's end): fold it as it is
            self._cut = None
        return self.rule.should_ask(count)

    def ask(self, count: int) -> HelpRequest:
        """Put the question (the rule's window starts afresh) and publish it."""
        goal = self.last_goal
        self.rule.asked()
        if self._cut is not None:
            self._fold(*self._cut)
            self._cut = None
        msg = HelpRequest(stamp=self.node.get_clock().now().to_msg(), index=self.rule.asks,
                          movement_index=count, goal=floats(goal))
        self._asked_at[msg.index] = count
        self._out.publish(msg)
        return msg

    def answered(self, demo: Demonstration) -> str:
        """Keep the teacher's answer; '' or why it is not an answer to an ask of this run."""
        index = int(demo.help_request)
        if index not in self._asked_at:
            return f"it answers help request {index}, which the learner never made"
        if index in self._answered:
            return f"help request {index} was answered already"
        if int(demo.movement_index) != self._asked_at[index]:
            return (f"it answers help request {index} at movement {int(demo.movement_index)}, "
                    f"but the learner asked at {self._asked_at[index]}")
        self._answered.add(index)
        self.answers[index] = demo
        return ""
