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

from rclpy.node import Node

from sgim_msgs.msg import Demonstration, HelpRequest
from sgim_nodes.core.schedule import Schedule
from sgim_nodes.nodes.ros_glue import floats
from sgim_ros.interfaces import publishes

HELP_REQUESTS = publishes("help_requests", "the learner asks for help: on request, or "
                          "sgim-acts")


def resume_schedule(schedule: Schedule, records, count: int, turns_taken) -> None:
    """Give the schedule a stopped run's teacher turns, asks and own goal attempts (the
    competences with a goal index), from its records."""
    schedule.resume(count, turns_taken,
                    [(h.movement_index, h.goal) for h in records.help_requests],
                    [(c.movement_index, c.goal, c.competence) for c in records.competences
                     if c.goal_index > 0])


class HelpAsks:
    """The schedule's asks published, and the teacher's answers kept."""

    def __init__(self, node: Node, schedule: Schedule) -> None:
        self.node = node
        self.schedule = schedule
        self.answers: dict[int, Demonstration] = {}  # answers not yet taken
        self._answered: set[int] = set()
        self._asked_at: dict[int, int] = {}  # ask index -> the count it was made at
        self._out = HELP_REQUESTS.create(node)


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
