"""The SGIM-ACTS choice figures of issue 33: whom the learner asks where, and how often."""

from __future__ import annotations

import numpy as np
import pytest

from sgim_nodes.analysis.strategy_choices import (
    Ask,
    asks_from_runner,
    expert_share,
    in_window,
    part_experts,
    strategy_shares,
    teacher_share,
)
from sgim_nodes.core.experts import ARM_EXPERTS, FISHING_EXPERTS, ExpertSpec


def test_each_part_has_the_one_precise_expert_that_names_it():
    assert part_experts(FISHING_EXPERTS) == {
        "basin": "centre", "north": "centre", "east": "centre",
        "west": "west", "south": "west", "pond": "west"}  # rough knows all, imprecisely
    assert part_experts(ARM_EXPERTS) == {}  # halves of the set, not parts of a world
    both = (ExpertSpec("a", "parts:basin+north"), ExpertSpec("b", "parts:north"))
    assert part_experts(both) == {"basin": "a"}  # north has no single expert


def test_shares_count_the_asks_of_the_last_window():
    parts = {(0.0, 0.0): "basin", (1.0, 0.0): "pond", (2.0, 0.0): "land"}

    def part_of(goal):
        return parts[tuple(float(x) for x in goal)]

    asks = [Ask(10, "rough", np.array([0.0, 0.0])),    # before the window
            Ask(900, "centre", np.array([0.0, 0.0])),  # the basin's expert
            Ask(950, "rough", np.array([1.0, 0.0])),   # the pond's is west
            Ask(990, "west", np.array([1.0, 0.0])),
            Ask(999, "west", np.array([2.0, 0.0]))]    # on land: nobody's part
    late = in_window(asks, 1000, 200)
    assert [a.movement for a in late] == [900, 950, 990, 999]
    share = expert_share(late, FISHING_EXPERTS, part_of)
    assert (share.hits, share.total, share.value) == (2, 3, pytest.approx(2 / 3))
    assert teacher_share(late, "rough").value == pytest.approx(1 / 4)
    assert teacher_share([], "rough").value is None
    assert len(in_window(asks, 1000, 0)) == 5


def test_a_runner_run_s_requests_and_choices_are_read_back():
    from sgim_nodes.core.acts_runner import experts_for, run_acts
    from sgim_nodes.core.learners import make_learner
    from sgim_nodes.core.runner import build_world

    world = build_world("fishing", 3)
    experts = experts_for("fishing", world, 3)
    learner = make_learner("sgim-acts", world.env.action_dim, world.env.outcome_dim, 3,
                           scale=world.scale, teachers=tuple(experts))
    records: list[dict] = []
    world.goals = world.goals[:5]  # the evaluations are not what is tested here
    run_acts(learner, world, 150, 0, experts, records.append)
    asks = asks_from_runner(records)
    assert len(asks) == learner.n_requests > 0
    assert {a.teacher for a in asks} <= set(experts)
    windows = strategy_shares(records, 150, 50)
    assert [start for start, _ in windows] == [0, 50, 100]
    for _, shares in windows:
        assert sum(shares.values()) == pytest.approx(1.0)
    chosen = [r["strategy"] for r in records if r["type"] == "strategy_choice"]
    assert set().union(*(s for _, s in windows)) == set(chosen)
    from sim_bridge.lake import Lake

    share = expert_share(asks, FISHING_EXPERTS, Lake().part_of_outcome)
    owned = [a for a in asks if Lake().part_of_outcome(a.goal) != "land"]
    assert share.total == len(owned)
