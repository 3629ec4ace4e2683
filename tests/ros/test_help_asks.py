"""The arbiter's side of timing on-request (nodes/help_asks.py) against the core's learner:
the same asks at the same counts about the same goals, the same windows, when goal attempts
end by themselves or are cut where an ask is earned; and the state a resumed run rebuilds."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from sgim_nodes.core.help_request import HelpRequests

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
    return HelpAsks(node, TOTAL, PERIOD), node


def _flat(_rng, n):
    """Competences with no progress: a level with a little noise, each half of a window the
    same mean (no gap, a standard error above zero: stalled)."""
    return [-0.5 + (0.01 if i % 2 else -0.01) for i in range(n)]


def test_a_stalled_learner_is_capped_at_its_next_ask_and_folds_the_cut_attempt_after_it():
    asks, node = _asks()
    rule = HelpRequests(asks.rule.budget, PERIOD)  # the core's, driven as the runner does
    rng = np.random.default_rng(0)
    count = 0
    for k, c in enumerate(_flat(rng, 20)):  # 20 one-movement attempts: stalled at 20
        count += 1
        asks.attempt_ended(np.array([0.01 * k, 0.0]), 1, c, True, count)
        rule.attempt_ended(c)
    assert asks.should_ask(count) and rule.should_ask(count)  # the first ask is earned
    ask = asks.ask(count)
    rule.asked()
    assert (ask.index, ask.movement_index) == (1, 20) and node.published == [ask]
    assert ask.goal == pytest.approx([0.19, 0.0])  # the latest attempt's goal
    for k, c in enumerate(_flat(rng, 20)):  # stalled again at 40, but ask 2 comes at 50
        count += 1
        asks.attempt_ended(np.array([0.5, 0.01 * k]), 1, c, True, count)
        rule.attempt_ended(c)
    assert rule.stalled() and not rule.should_ask(count) and not asks.should_ask(count)
    assert count == 40 and asks.cap(count, 460) == 10  # the next attempt stops at 50
    # It runs 10 movements and is cut at 50, where ask 2 is earned: the runner's learner
    # asks first (about the latest attempt folded), then folds the one its ask interrupts.
    cut_goal = np.array([-0.3, 0.3])
    asks.attempt_ended(cut_goal, 10, -0.9, False, 50)
    assert asks.should_ask(50) and rule.should_ask(50)
    ask = asks.ask(50)
    rule.asked()
    rule.attempt_ended(-0.9)
    assert ask.index == 2 and ask.goal == pytest.approx([0.5, 0.19])  # not the cut one's
    assert asks.rule._recent == rule._recent == [-0.9]
    assert np.array_equal(asks.last_goal, cut_goal)


def test_an_attempt_that_ends_by_itself_at_the_boundary_is_folded_before_the_ask():
    asks, _ = _asks()
    rng = np.random.default_rng(1)
    for k, c in enumerate(_flat(rng, 19)):
        asks.attempt_ended(np.array([0.0, 0.01 * k]), 1, c, True, k + 1)
    assert not asks.rule.stalled()
    asks.attempt_ended(np.array([0.7, 0.7]), 1, -0.5, True, 20)  # the 20th: now stalled
    assert asks.should_ask(20)
    assert asks.ask(20).goal == pytest.approx([0.7, 0.7])


def test_no_cap_without_a_stall_nor_once_the_budget_is_spent():
    asks, _ = _asks()
    assert asks.cap(0, 100) == 100  # nothing attempted: no stall
    rng = np.random.default_rng(2)
    for k, c in enumerate(_flat(rng, 20)):
        asks.attempt_ended(np.array([0.0, 0.0]), 1, c, True, k + 1)
    asks.rule.asks = asks.rule.budget
    assert asks.rule.stalled() and not asks.should_ask(495) and asks.cap(21, 479) == 479


def test_answers_are_kept_once_and_only_for_asks_made_at_their_count():
    asks, _ = _asks()
    demo = SimpleNamespace(help_request=1, movement_index=20)
    assert "never made" in asks.answered(demo)
    for c in _flat(None, 20):
        asks.attempt_ended(np.zeros(2), 1, c, True, 20)
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
    asks.resume(records, 50)  # the ask at 60 is after the resumed count
    return asks


def test_a_resumed_run_counts_its_asks_and_refills_the_window_since_the_last():
    asks = _resumed(ask_goal=[0.0, 0.10])  # attempt 10 ended by itself, then the ask
    assert asks.rule.asks == 1
    assert asks.rule._recent == pytest.approx([-0.1 * k for k in range(11, 20)])
    assert asks.last_goal == pytest.approx([0.0, 0.19])


def test_a_resumed_run_puts_the_attempt_an_ask_cut_after_the_ask_as_the_live_run_did():
    asks = _resumed(ask_goal=[0.0, 0.09])  # the ask named attempt 9: it cut attempt 10
    assert asks.rule.asks == 1
    assert asks.rule._recent == pytest.approx([-0.1 * k for k in range(10, 20)])
