"""SGIM-ACTS's strategies: parsing, costs, and the refusals that keep a run well defined."""

import pytest

from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.strategies import (
    Strategy,
    all_strategies,
    parse_strategies,
    parse_strategy,
)


def test_names_parse_into_kind_teacher_and_the_configured_cost():
    cfg = LearnerConfig(acts_cost_autonomous=1.5, acts_cost_emulation=3.0,
                        acts_cost_mimicry=7.0)
    auto = parse_strategy("autonomous", cfg)
    mimic = parse_strategy("mimicry:west", cfg, teachers=("west", "east"))
    emul = parse_strategy(" emulation:east ", cfg, teachers=("west", "east"))
    assert (auto.kind, auto.teacher, auto.cost, auto.social) == ("autonomous", None, 1.5, False)
    assert (mimic.name, mimic.cost, mimic.wants_action) == ("mimicry:west", 7.0, True)
    assert (emul.name, emul.teacher, emul.cost, emul.wants_action) == (
        "emulation:east", "east", 3.0, False)
    assert parse_strategy("mimicry:west", cfg, cost=2.5).cost == 2.5


def test_default_costs_make_a_demonstration_dearer_than_a_movement():
    cfg = LearnerConfig()
    costs = {s.kind: s.cost for s in all_strategies(["t"], cfg)}
    assert costs["autonomous"] < costs["emulation"] < costs["mimicry"]


def test_all_strategies_lists_autonomous_then_both_social_ones_per_teacher():
    names = [s.name for s in all_strategies(["west", "rough"])]
    assert names == ["autonomous", "mimicry:west", "emulation:west", "mimicry:rough",
                     "emulation:rough"]


@pytest.mark.parametrize("text, message", [
    ("imitation:west", "write autonomous, mimicry:NAME or emulation:NAME"),
    ("", "write autonomous"),
    ("autonomous:west", "autonomous asks no teacher"),
    ("mimicry", "mimicry needs a teacher"),
    ("emulation:", "emulation needs a teacher"),
    ("mimicry:we st", "bad teacher name"),
    ("mimicry:west-1", "bad teacher name"),  # not a ROS namespace: the node could not be
    ("emulation:2nd", "bad teacher name"),
    ("mimicry:north", "unknown teacher 'north'; known teachers: west, east"),
])
def test_bad_strategy_names_and_unknown_teachers_are_refused(text, message):
    with pytest.raises(ValueError, match=message):
        parse_strategy(text, teachers=("west", "east"))


def test_a_strategy_list_must_be_non_empty_and_name_each_once():
    with pytest.raises(ValueError, match="at least one strategy"):
        parse_strategies([])
    with pytest.raises(ValueError, match="named twice: mimicry:west"):
        parse_strategies(["mimicry:west", "autonomous", "mimicry:west"], teachers=["west"])


@pytest.mark.parametrize("cost", [-1.0, 0.0, float("inf"), float("nan")])
def test_negative_zero_or_infinite_costs_are_refused(cost):
    with pytest.raises(ValueError, match="cost must be a finite number > 0"):
        Strategy("mimicry", "west", cost)
    with pytest.raises(ValueError, match="cost must be a finite number > 0"):
        parse_strategy("autonomous", cost=cost)


@pytest.mark.parametrize("field", ["acts_cost_autonomous", "acts_cost_emulation",
                                   "acts_cost_mimicry"])
def test_the_config_refuses_non_positive_costs(field):
    with pytest.raises(ValueError, match=f"LearnerConfig.{field}: must be > 0"):
        LearnerConfig(**{field: -2.0})


def test_a_strategy_kind_and_its_teacher_must_agree():
    with pytest.raises(ValueError, match="autonomous strategies take no teacher"):
        Strategy("autonomous", "west", 1.0)
    with pytest.raises(ValueError, match="emulation strategies take a teacher"):
        Strategy("emulation", None, 1.0)
    with pytest.raises(ValueError, match="unknown strategy kind"):
        Strategy("babbling", None, 1.0)
