"""The arbiter's side of timing on-request: the learner's asks as HelpRequest messages, and
the teacher's answers kept until the arbiter takes them.

When to ask, about which goal, and which goal attempts count, is the core's schedule
(core/schedule.py), which the single-process runner drives too: the arbiter tells it every
goal attempt that spent a movement (a drawn goal, or a goal-only demonstration's outcome
adopted as a goal; never an imitation) and caps its jobs where the schedule says the next ask
comes. The ask is a HelpRequest on `help_requests` about the goal of the latest attempt
folded; the teacher answers on `demonstrations` with a Demonstration whose `help_request`
names it.
"""

from __future__ import annotations

import numpy as np
from rclpy.node import Node

from sgim_msgs.msg import Demonstration, HelpRequest
from sgim_nodes.core.schedule import Schedule
from sgim_nodes.nodes.ros_glue import floats
from sgim_ros.interfaces import publishes

HELP_REQUESTS = publishes("help_requests", "the learner asks for help: on request, or "
                          "sgim-acts")


class HelpAsks:
    """The schedule's asks published, and the teacher's answers kept."""

    def __init__(self, node: Node, schedule: Schedule) -> None:
        self.node = node
        self.schedule = schedule
        self.answers: dict[int, Demonstration] = {}  # answers not yet taken
        self._answered: set[int] = set()
        self._asked_at: dict[int, int] = {}  # ask index -> the count it was made at
        self._out = HELP_REQUESTS.create(node)

    def resume(self, records, count: int) -> None:
        """Asks already made and the window since the last one, from a run's records (the
        competences of own goal attempts: those with a goal index).

        An attempt that ends where the last ask was made went into the window before the ask
        if it ended by itself, after it if the ask cut it; the ask's goal tells which, since it
        is the goal of the latest attempt folded before the ask. One case stays open: a run
        stopped right where an ask was due, before it was made, whose last attempt the ask
        would have cut is folded as if it had ended by itself."""
        asks = [h for h in records.help_requests if h.movement_index < count]
        self.schedule.help.asks = len(asks)
        last = asks[-1] if asks else None
        own = [c for c in records.competences if c.goal_index > 0 and c.movement_index <= count]
        for c in own:
            if last is None or c.movement_index > last.movement_index or (
                    c.movement_index == last.movement_index
                    and not np.allclose(c.goal, last.goal)):  # the attempt the ask cut
                self.schedule.help.attempt_ended(c.competence)
        if own:
            self.schedule.last_goal = np.asarray(own[-1].goal, dtype=float)

    def ask(self, count: int) -> HelpRequest:
        """Put the schedule's question and publish it."""
        question = self.schedule.ask(count)
        msg = HelpRequest(stamp=self.node.get_clock().now().to_msg(), index=question.index,
                          movement_index=count, goal=floats(question.goal))
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
