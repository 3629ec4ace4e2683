"""docs/reference.md states every rule a run's parameters must keep (not only each one's own
range) and every learner whose graph holds a node; both come from the code's declarations."""

from __future__ import annotations

import pytest

from tests.conftest import REPO

pytestmark = pytest.mark.ros  # the graph's description imports the nodes' PARAMS

PAGE = REPO / "docs" / "reference.md"


def _ranges(name: str) -> list[str]:
    """The range column of every row of the page for the parameter `name`."""
    rows = [line for line in PAGE.read_text(encoding="utf-8").splitlines()
            if line.startswith(f"| `{name}` |")]
    assert rows, name
    return [row.split(" | ")[2] for row in rows]


def test_the_page_states_each_rule_that_ties_learner_parameters():
    from sgim_nodes.core.config import TIES

    stated = {(name, tie.rule) for tie in TIES for name in tie.fields}
    assert {("zeta", "even"), ("zeta", "zeta <= max_goals_per_region"),
            ("p_mode2", "p_mode1 + p_mode2 + p_mode3 = 1")} <= stated
    for name, rule in stated:
        for cell in _ranges(name):
            assert rule in cell.split("; "), (name, cell)


def test_each_tie_is_what_the_learner_config_refuses():
    """A configuration that breaks one tie and nothing else is refused, naming the tie's
    first field with its words; the defaults keep every tie."""
    import dataclasses
    import re

    from sgim_nodes.core.config import TIES, LearnerConfig

    default = LearnerConfig()
    assert all(tie.holds(default) for tie in TIES)
    breaking = [{"zeta": 51}, {"zeta": 102}, {"min_goals_per_child": 51}, {"p_mode1": 0.5}]
    for tie, change in zip(TIES, breaking, strict=True):
        with pytest.raises(ValueError, match=re.escape(f"LearnerConfig.{tie.fields[0]}: "
                                                       f"{tie.refusal} (got")):
            dataclasses.replace(default, **change)


def test_the_teachers_wait_has_its_floor_on_the_page():
    assert _ranges("teacher_timeout") == [">= 1"]


def test_the_web_teacher_is_in_the_graph_of_each_learner_it_teaches():
    """SGIM-ACTS asks the web page as one of its teachers (--teacher web): its graph holds
    the web teacher, and the page says so."""
    from sgim_nodes.graph.description import NODES
    from sgim_nodes.graph.reference import run_graph, who_runs

    assert NODES["web_teacher"] in run_graph("sgim-acts", "web", True)
    text = who_runs(NODES["web_teacher"])
    assert text == "sgim-d, demo-only, sgim-acts (teacher web)"
    assert f"- in the graph of: {text}" in PAGE.read_text(encoding="utf-8")
