"""The strategy pre-check tool: forced strategies on goals of each expert's part, and both
counts printed, on one seed with few goals."""

from __future__ import annotations

import re

import pytest

from sgim_nodes.core.experts import FISHING_EXPERTS
from sgim_nodes.core.random_streams import member_rng
from sgim_nodes.core.runner import build_world
from sgim_nodes.experiments import strategy_precheck as precheck

NAMES = {"autonomous", *(f"{kind}:{t.name}" for t in FISHING_EXPERTS
                         for kind in ("mimicry", "emulation"))}


def test_it_prints_both_rankings_per_part_and_both_counts(capsys):
    assert precheck.main(["--seeds", "0", "--goals", "3", "--warmup", "30"]) == 0
    out = capsys.readouterr().out
    assert out.count("  gain:  ") == out.count("  eq. 2: ") == 2  # two parted experts
    for kind in ("mimicry", "emulation"):
        assert re.search(rf"^{kind}: own expert above rough in [0-2] of 2 comparisons with "
                         rf"the gain value, [0-2] of 2 with eq\. 2$", out, re.MULTILINE), out


def test_every_strategy_is_tried_on_the_part_and_the_values_are_the_cores():
    results = precheck.check_seed(0, 30, 3, precheck.LearnerConfig())
    assert [r.expert for r in results] == ["centre", "west"]  # rough knows no single part
    for r in results:
        assert set(r.gain) == set(r.interest) == NAMES
        assert r.episodes == dict.fromkeys(NAMES, 3)  # each strategy, forced, on each goal
        assert all(0.0 <= g <= 1.0 for g in r.gain.values())
        assert all(v >= 0.0 for v in r.interest.values())
    # the other part's expert says "none there" about every goal: competence -1, gain 0
    assert results[0].gain["mimicry:west"] == results[1].gain["mimicry:centre"] == 0.0


def test_goals_are_drawn_inside_the_experts_part_only():
    world = build_world("fishing", 0)
    for spec in precheck.parted_experts():
        goals = precheck.part_goals(world, spec.named_parts, 20, member_rng(0, "goals", "t"))
        assert {world.part_of(g) for g in goals} <= set(spec.named_parts)


@pytest.mark.parametrize("text, seeds", [("10-12", [10, 11, 12]), ("3,5", [3, 5]),
                                         ("1,4-5", [1, 4, 5])])
def test_seed_lists_parse(text, seeds):
    assert precheck.parse_seeds(text) == seeds


def test_bad_seed_lists_are_refused():
    with pytest.raises(SystemExit):
        precheck.main(["--seeds", "9-3"])
