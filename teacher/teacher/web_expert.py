"""The web teacher as one of SGIM-ACTS's experts (issue 33): a person answers its requests.

With its `expert` parameter true (`run_experiment.sh sgim-acts --teacher web` puts "web"
among the learner's `teachers`), the web teacher no longer speaks when it likes: the learner
asks it, as it asks the expert nodes (teacher/expert_node.py), and the person answers each
request from the page. Every demonstration the person makes (a teaching entry, a confirmed
offer, a pasted action) answers the oldest open request: with its action and outcome for
mimicry (means-and-goal), its outcome only for emulation (goal-only); the page's "none there"
answers that the person has nothing to show near the asked goal. The page's log says each
request as it comes, and the strategy and teacher the learner chose for every episode (the
goal generator's Goal.strategy), so the person sees whom the learner asks, and how.

Interfaces (absolute names, as an expert node's):
  subscribes  /help_requests (those naming it), goals (the episodes' strategies)
  publishes   /demonstrations (source "expert:NAME", help_request = the request's index)
  serves      web/expert_ready (the arbiter waits for it before the first movement)
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from rclpy.node import Node

from sgim_msgs.msg import Demonstration, Goal, HelpRequest
from sgim_nodes.bag.record_checks import Limits, expert_source
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.teaching import GOAL_ONLY, MEANS_AND_GOAL
from sgim_ros.interfaces import serves, subscribes
from sgim_ros.ready import serve_ready
from teacher.human_commands import CommandError, NoneThere  # noqa: F401 - the page's command

WEB_EXPERT = "web"
# With the parameter `expert`, in the web teacher's INTERFACES (its node is in the root
# namespace: the ready service is /web/expert_ready, where the arbiter asks).
AS_EXPERT = "expert: the web page is one of sgim-acts's teachers"
REQUESTS, GOALS = subscribes("/help_requests", AS_EXPERT), subscribes("goals", AS_EXPERT)
READY = serves(f"{WEB_EXPERT}/expert_ready", AS_EXPERT)
WEB_EXPERT_INTERFACES = (REQUESTS, GOALS, READY)
"""The name the web teacher answers SGIM-ACTS's requests under (a run's `teachers` lists it)."""


def episode_line(goal: Goal) -> str:
    """How the page's log says an episode: its movement, strategy and goal."""
    point = ", ".join(f"{v:.2f}" for v in goal.point)
    return f"episode at movement {goal.movement_index}: {goal.strategy} toward ({point})"


class WebExpert:
    """The requests naming the web teacher, and its answers (module docstring)."""

    def __init__(self, node: Node, say: Callable[[str, str], None]) -> None:
        self.node, self.name, self.say = node, WEB_EXPERT, say
        self.source = expert_source(WEB_EXPERT)
        self.open: list[HelpRequest] = []
        # The learner's requests are signed by its arbiter: a forged one is never shown.
        self.gate = LiveGate(node.get_logger().warning, Limits())
        self.answered: set[int] = set()
        requests = REQUESTS.create(node, self._on_request)
        GOALS.create(node, self._on_goal)
        serve_ready(node, READY, {"help_requests": requests})

    def _on_goal(self, goal: Goal) -> None:
        if goal.strategy:
            self.say(episode_line(goal), "info")

    def _on_request(self, msg: HelpRequest) -> None:
        if msg.teacher != self.name or self.gate.check("help_requests", msg):
            return
        if msg.index in self.answered or any(
                r.index == msg.index for r in self.open):
            return
        self.open.append(msg)
        what = ("its action and outcome (mimicry)" if msg.content == MEANS_AND_GOAL
                else "the outcome to reach (emulation)")
        point = ", ".join(f"{v:.2f}" for v in msg.goal)
        self.say(f"request {msg.index}: the learner asks you for {what} near ({point}); "
                 "demonstrate, or answer 'none there'", "sent")

    def answer(self, stamp, number: int, action, outcome, teaching_set_index: int
               ) -> Demonstration:
        """The person's demonstration as the answer to the oldest open request."""
        ask = self._oldest()
        goal_only = ask.content == GOAL_ONLY
        return Demonstration(
            stamp=stamp, index=number, movement_index=ask.movement_index,
            action=[] if goal_only else [float(v) for v in action],
            outcome=[float(v) for v in outcome], teaching_set_index=teaching_set_index,
            source=self.source, content=ask.content or MEANS_AND_GOAL, help_request=ask.index)

    def none_there(self, stamp) -> Demonstration:
        """An empty answer to the oldest open request: nothing near its goal."""
        ask = self._oldest()
        return Demonstration(stamp=stamp, movement_index=ask.movement_index,
                             teaching_set_index=-1, source=self.source,
                             content=ask.content or MEANS_AND_GOAL, help_request=ask.index)

    def _oldest(self) -> HelpRequest:
        if not self.open:
            raise CommandError("the learner has not asked you anything yet: wait for its "
                               "request (the log says it)")
        ask = self.open.pop(0)
        self.answered.add(ask.index)
        return ask

    @staticmethod
    def describe(demo: Demonstration) -> str:
        goal = "" if not len(demo.outcome) else f" outcome {np.round(demo.outcome, 3)}"
        return f"answered request {demo.help_request}{goal or ': none there'}"
