"""The arbiter's side of timing on-request (nodes/help_asks.py): the schedule's asks
published, the teacher's answers kept, and the state a resumed run rebuilds (the rule itself
is the core's schedule: tests/core/test_schedule.py)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from sgim_nodes.core.help_request import ON_REQUEST
from sgim_nodes.core.schedule import Schedule

pytestmark = pytest.mark.ros

PERIOD, TOTAL = 50, 500


class _Node:
    """What HelpAsks needs of a node: a publisher (kept) and a clock."""

    def __init__(self) -> None:
        self.published: list = []

    def create_publisher(self, _type, _topic, _qos):
        return SimpleNamespace(publish=self.published.append)

    def get_clock(self):
        from builtin_interfaces.msg import Time

        return SimpleNamespace(now=lambda: SimpleNamespace(to_msg=Time))


def _asks():
    from sgim_nodes.nodes.help_asks import HelpAsks

    node = _Node()
    return HelpAsks(node, Schedule(TOTAL, PERIOD, ON_REQUEST, teacher=True)), node


def _flat(_rng, n):
    """Competences with no progress: a level with a little noise, each half of a window the
    same mean (no gap, a standard error above zero: stalled)."""
    return [-0.5 + (0.01 if i % 2 else -0.01) for i in range(n)]


def test_answers_are_kept_once_and_only_for_asks_made_at_their_count():
    asks, _ = _asks()
    demo = SimpleNamespace(help_request=1, movement_index=20)
    assert "never made" in asks.answered(demo)
    for c in _flat(None, 20):
        asks.schedule.attempt_ended(np.zeros(2), c)
    asks.ask(20)
    assert "asked at 20" in asks.answered(SimpleNamespace(help_request=1, movement_index=21))
    assert asks.answered(demo) == "" and asks.answers == {1: demo}
    asks.answers.pop(1)
    assert "answered already" in asks.answered(demo) and asks.answers == {}


def _resumed(ask_goal):
    """A run resumed at 50 whose one ask came at 30, where own attempt 10 ended."""
    asks, _ = _asks()
    ask = SimpleNamespace(movement_index=30, goal=ask_goal)
    own = [SimpleNamespace(goal_index=k, movement_index=10 + 2 * k, competence=-0.1 * k,
                           goal=[0.0, 0.01 * k]) for k in range(1, 20)]
    imitation = SimpleNamespace(goal_index=0, movement_index=33, competence=-0.9, goal=[1, 1])
    records = SimpleNamespace(help_requests=[ask, SimpleNamespace(movement_index=60, goal=[])],
                              competences=[*own, imitation])
    from sgim_nodes.nodes.help_asks import resume_schedule

    resume_schedule(asks.schedule, records, 50, [])  # the ask at 60 is after the count
    return asks


def test_a_resumed_run_counts_its_asks_and_refills_the_window_since_the_last():
    asks = _resumed(ask_goal=[0.0, 0.10])  # attempt 10 ended by itself, then the ask
    assert asks.schedule.help.asks == 1
    assert asks.schedule.help._recent == pytest.approx([-0.1 * k for k in range(11, 20)])
    assert asks.schedule.last_goal == pytest.approx([0.0, 0.19])


def test_a_resumed_run_puts_the_attempt_an_ask_cut_after_the_ask_as_the_live_run_did():
    asks = _resumed(ask_goal=[0.0, 0.09])  # the ask named attempt 9: it cut attempt 10
    assert asks.schedule.help.asks == 1
    assert asks.schedule.help._recent == pytest.approx([-0.1 * k for k in range(10, 20)])
