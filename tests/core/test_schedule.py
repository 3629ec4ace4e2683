"""The learner's schedule (core/schedule.py), which both the runner and the graph's arbiter
drive: the teacher's turns, the learner's asks against the core's rule driven movement by
movement as the runner's learner drives it, and the caps a job gets from both."""

from __future__ import annotations

import numpy as np
import pytest

from sgim_nodes.core.help_request import ON_REQUEST, PERIOD, HelpRequests
from sgim_nodes.core.schedule import Schedule

P, TOTAL = 50, 500


def _flat(n):
    """Competences with no progress: a level with a little noise, each half of a window the
    same mean (no gap, a standard error above zero: stalled)."""
    return [-0.5 + (0.01 if i % 2 else -0.01) for i in range(n)]


def _asking() -> Schedule:
    return Schedule(TOTAL, P, ON_REQUEST, teacher=True)


def test_the_teacher_is_due_every_period_once_and_jobs_stop_at_its_turns():
    schedule = Schedule(TOTAL, P, PERIOD, teacher=True)
    assert [c for c in range(TOTAL) if schedule.turn_due(c)] == list(range(0, TOTAL, P))
    schedule.take_turn(100)
    assert not schedule.turn_due(100) and schedule.turn_due(150)
    assert not schedule.turn_due(TOTAL)  # the budget is spent: no turn after it
    assert [schedule.cap(c) for c in (0, 1, 49, 50, 480)] == [50, 49, 1, 50, 20]
    assert schedule.help is None and not schedule.ask_due(100)


def test_without_a_teacher_nothing_interrupts_the_learner():
    for timing in (PERIOD, ON_REQUEST):
        schedule = Schedule(TOTAL, P, timing, teacher=False)
        assert not any(schedule.turn_due(c) or schedule.ask_due(c) for c in range(TOTAL))
        assert schedule.cap(120) == TOTAL - 120


def test_on_request_there_are_no_turns_and_no_cap_without_a_stall():
    schedule = _asking()
    assert not any(schedule.turn_due(c) for c in range(TOTAL))
    assert schedule.cap(0) == TOTAL  # nothing attempted: no stall


def test_a_stalled_learner_is_capped_at_its_next_ask_and_folds_the_cut_attempt_after_it():
    schedule = _asking()
    rule = HelpRequests(schedule.help.budget, P)  # the core's rule, as the runner drove it
    count = 0
    for k, c in enumerate(_flat(20)):  # 20 one-movement attempts: stalled at 20
        count += 1
        schedule.attempt_ended(np.array([0.01 * k, 0.0]), c)
        rule.attempt_ended(c)
    assert schedule.ask_due(count) and rule.should_ask(count)  # the first ask is earned
    ask = schedule.ask(count)
    rule.asked()
    assert (ask.index, ask.movement) == (1, 20)
    assert ask.goal == pytest.approx([0.19, 0.0])  # the latest attempt's goal
    for k, c in enumerate(_flat(20)):  # stalled again at 40, but ask 2 comes at 50
        count += 1
        schedule.attempt_ended(np.array([0.5, 0.01 * k]), c)
        rule.attempt_ended(c)
    assert rule.stalled() and not rule.should_ask(count) and not schedule.ask_due(count)
    assert count == 40 and schedule.cap(count) == 10  # the next attempt stops at 50
    # It runs 10 movements and is cut at 50, where ask 2 is earned: the learner asks first
    # (about the latest attempt folded), then folds the one its ask interrupts.
    cut_goal = np.array([-0.3, 0.3])
    schedule.attempt_ended(cut_goal, -0.9, cut_at=50)
    assert schedule.ask_due(50) and rule.should_ask(50)
    ask = schedule.ask(50)
    rule.asked()
    rule.attempt_ended(-0.9)
    assert ask.index == 2 and ask.goal == pytest.approx([0.5, 0.19])  # not the cut one's
    assert schedule.help._recent == rule._recent == [-0.9]
    assert np.array_equal(schedule.last_goal, cut_goal)


def test_an_attempt_that_ends_by_itself_at_the_boundary_is_folded_before_the_ask():
    schedule = _asking()
    for k, c in enumerate(_flat(19)):
        schedule.attempt_ended(np.array([0.0, 0.01 * k]), c)
    assert not schedule.help.stalled()
    schedule.attempt_ended(np.array([0.7, 0.7]), -0.5)  # the 20th: now stalled
    assert schedule.ask_due(20)
    assert schedule.ask(20).goal == pytest.approx([0.7, 0.7])


def test_an_attempt_cut_where_no_ask_comes_is_folded_as_it_is():
    schedule = _asking()
    for c in _flat(19):
        schedule.attempt_ended(np.zeros(2), c)
    schedule.attempt_ended(np.ones(2), -0.5, cut_at=10)  # cut, but no ask is earned there
    assert len(schedule.help._recent) == 20 and np.array_equal(schedule.last_goal, np.ones(2))


def test_no_cap_once_every_ask_is_spent():
    schedule = _asking()
    for c in _flat(20):
        schedule.attempt_ended(np.zeros(2), c)
    schedule.help.asks = schedule.help.budget
    assert schedule.help.stalled() and not schedule.ask_due(495)
    assert schedule.cap(21) == TOTAL - 21


@pytest.mark.parametrize(("budget", "period"), [(-1, 10), (10, 0)])
def test_a_schedule_refuses_a_negative_budget_or_a_period_below_one(budget, period):
    with pytest.raises(ValueError, match="budget >= 0 and period >= 1"):
        Schedule(budget, period, PERIOD, teacher=True)


def _drive(schedule: Schedule, stop: int, seed: int = 3):
    """One-movement own attempts with a stalled competence, asks put when due, each 7th
    attempt cut by its job at the boundary: the records a run keeps, up to ``stop``."""
    rng = np.random.default_rng(seed)
    asks, attempts, turns = [], [], []
    for count in range(1, stop + 1):
        goal, competence = rng.uniform(-1, 1, 2), -0.5 + rng.normal(0, 0.01)
        schedule.attempt_ended(goal, competence, cut_at=count if count % 7 == 0 else None)
        attempts.append((count, goal, competence))
        if schedule.ask_due(count):
            ask = schedule.ask(count)
            asks.append((ask.movement, ask.goal))
        if schedule.turn_due(count):
            schedule.take_turn(count)
            turns.append(count)
    return asks, attempts, turns


@pytest.mark.parametrize("stop", [57, 150, 263, 357])
def test_a_schedule_resumed_from_its_records_goes_on_as_the_uninterrupted_one(stop):
    """Stopped at ``stop`` and resumed from what the run recorded (the asks put before it, the
    attempts up to it), the schedule asks at the same movements about the same goals as the
    schedule that was never stopped, from the boundary at ``stop`` on."""
    whole = _asking()
    asks, attempts, _ = _drive(whole, TOTAL)
    resumed = _asking()
    resumed.resume(stop, [], [a for a in asks if a[0] < stop],
                   [a for a in attempts if a[0] <= stop])
    if all(m != stop for m, _ in asks):  # then also the same state as the one never stopped
        again = _asking()
        _drive(again, stop)
        assert (resumed.help.asks, resumed.help._recent) == (again.help.asks, again.help._recent)
        assert np.array_equal(resumed.last_goal, again.last_goal)
    rest = []
    if resumed.ask_due(stop):
        rest.append(resumed.ask(stop))
    for count, goal, competence in (a for a in attempts if a[0] > stop):
        resumed.attempt_ended(goal, competence, cut_at=count if count % 7 == 0 else None)
        if resumed.ask_due(count):
            rest.append(resumed.ask(count))
    expected = [(m, g) for m, g in asks if m >= stop]
    assert [a.movement for a in rest] == [m for m, _ in expected]
    assert all(np.allclose(a.goal, g) for a, (_, g) in zip(rest, expected, strict=True))
    assert any(m % 7 == 0 and m < stop for m, _ in asks) or stop < 350  # an ask that cut


def test_a_resumed_schedule_keeps_the_teacher_turns_taken():
    schedule = Schedule(TOTAL, P, PERIOD, teacher=True)
    schedule.resume(120, [0, 50, 100], [], [])
    assert not schedule.turn_due(100) and schedule.turn_due(150)
