"""Demonstrations on request (issue 14, ``timing: on-request``): the learner asks when its
competence progress stalls, within the periodic teacher's budget; the teacher answers for the
goal the learner was trying to reach. On the planar arm."""

from __future__ import annotations

import numpy as np
import pytest

from sgim_nodes.core import runner
from sgim_nodes.core.help_request import (
    ON_REQUEST,
    HelpRequests,
    budget_for,
    progress_and_error,
)
from sgim_nodes.core.social_config import SocialConfig
from sgim_nodes.core.teaching import Teacher


def test_progress_and_its_standard_error_by_hand():
    gap, se = progress_and_error(np.array([-0.5, -0.3, -0.1, -0.1]))  # halves -0.4 and -0.1
    assert gap == pytest.approx(0.3)
    assert se == pytest.approx(np.sqrt((0.02 + 0.0) / 2))


def test_asks_when_flat_not_while_progressing_then_waits_a_new_window():
    r = HelpRequests(budget=5, period=10, window=6)
    for c in [-0.9, -0.7, -0.5, -0.3, -0.2, -0.1]:  # steady progress: no ask
        r.attempt_ended(c)
    assert not r.stalled() and not r.should_ask(100)
    for c in [-0.5, -0.6, -0.5, -0.6, -0.5, -0.6]:  # flat within its noise: stalled
        r.attempt_ended(c)
    assert r.should_ask(100)
    r.asked()
    assert r.asks == 1 and not r.should_ask(100)  # a fresh window first
    for c in [-0.5] * 5:
        r.attempt_ended(c)
    assert not r.should_ask(100)
    r.attempt_ended(-0.5)
    assert r.should_ask(100)


def test_never_more_asks_than_earned_nor_than_the_budget():
    r = HelpRequests(budget=3, period=10, window=4)
    asked_at = []
    for movement in range(0, 60, 2):  # stalled all along: asks as soon as each is earned
        for _ in range(4):
            r.attempt_ended(-1.0)
        if r.should_ask(movement):
            r.asked()
            asked_at.append(movement)
    assert asked_at == [0, 10, 20]  # one per period, then the budget is spent
    assert [r.allowance(m) for m in (0, 9, 10, 25, 1000)] == [1, 1, 2, 3, 3]
    assert budget_for(5000, 150) == 34 and budget_for(300, 50) == 6


def test_bad_settings_refused():
    with pytest.raises(ValueError):
        HelpRequests(budget=-1, period=10)
    with pytest.raises(ValueError):
        HelpRequests(budget=3, period=10, window=5)
    with pytest.raises(ValueError):
        HelpRequests(budget=3, period=0)


def test_the_teacher_answers_with_the_unreached_entry_nearest_the_asked_goal():
    outcomes = np.array([[0.0, 0.0], [0.5, 0.0], [0.9, 0.0]])
    t = Teacher(np.zeros((3, 2)), outcomes, np.random.default_rng(0), tolerance=0.05)
    nothing = np.empty((0, 2))
    assert t.answer(np.array([0.6, 0.1]), nothing).index == 1
    assert t.answer(np.array([0.6, 0.1]), np.array([[0.5, 0.01]])).index == 2  # 1 reached
    assert t.answer(np.array([0.0, 0.0]), outcomes) is None


@pytest.mark.slow
def test_the_runner_teaches_only_when_asked_for_the_goal_asked_about():
    world = runner.build_world("planar-arm", 4)
    learner = runner.make_learner("sgim-d", 12, 2, 4, None, world.scale)
    records: list[dict] = []
    movements, period = 1500, 150
    social = SocialConfig(demonstration_period=period, tolerance_noise=0.01,
                          timing=ON_REQUEST)  # nothing is ever reached
    runner.run(learner, world, movements, 0, 4, records.append, social)
    asks = [r for r in records if r["type"] == "help_request"]
    demos = [r for r in records if r["type"] == "demonstration"]
    assert 0 < len(asks) <= budget_for(movements, period)
    assert all(a["ask"] <= a["movement"] // period + 1 for a in asks)  # never ahead of P
    # One demonstration per ask (some teaching goal always stays unreached), at the ask's
    # movement, and for the unreached teaching entry nearest the goal asked about. At this
    # tolerance the learner reaches an entry only by reproducing its demonstration, so every
    # entry nearer to the asked goal than the one shown must have been shown before.
    assert [d["movement"] for d in demos] == [a["movement"] for a in asks]
    goals = world.teaching_outcomes
    shown_before: set[int] = set()
    for ask, demo in zip(asks, demos, strict=True):
        distance = np.linalg.norm(goals - np.asarray(ask["goal"]), axis=1)
        nearer = set(np.flatnonzero(distance < distance[demo["teaching_index"]]).tolist())
        assert nearer <= shown_before, (ask["movement"], nearer - shown_before)
        assert demo["asked_goal"] == ask["goal"]
        shown_before.add(demo["teaching_index"])
    # Not the periodic turns: the asks fall where the learner stalled, not every P movements.
    assert [a["movement"] for a in asks] != list(range(0, movements, period))[:len(asks)]


def test_the_periodic_teacher_is_unchanged_by_the_timing_option():
    def demos(**timing):
        world = runner.build_world("planar-arm", 5)
        learner = runner.make_learner("sgim-d", 12, 2, 5, None, world.scale)
        records: list[dict] = []
        runner.run(learner, world, 300, 0, 5, records.append,
            SocialConfig(demonstration_period=50, **timing))
        return [(r["movement"], r["teaching_index"]) for r in records
                if r["type"] == "demonstration"]

    assert demos() == demos(timing="period")
    assert [m for m, _ in demos()][:1] == [0]


def test_demo_only_cannot_ask():
    world = runner.build_world("planar-arm", 0)
    learner = runner.make_learner("demo-only", 12, 2, 0, None, world.scale)
    with pytest.raises(ValueError, match="never asks"):
        runner.run(learner, world, 10, 0, 0, lambda r: None, SocialConfig(timing=ON_REQUEST))
