"""A replay of an SGIM-ACTS run (experiments/acts_values.py) lands where the runner lands, gives
each episode the values its chooser used, and refuses a run it does not reproduce."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from sgim_nodes.experiments import acts_values, pinned
from tests.golden_runs import EVAL_EVERY, MOVEMENTS, runner_records

pytestmark = pytest.mark.slow


def short(name: str):
    """The experiment's run `name`, cut to the golden runs' budget."""
    spec = next(s for s in pinned.find("active_strategies").graph_runs if s.name == name)
    return dataclasses.replace(spec, movements=MOVEMENTS, eval_every=EVAL_EVERY)


def test_the_replay_lands_where_the_runner_lands():
    values = acts_values.replay(short("sgim-acts-seed0"))
    moves = [r for r in runner_records("sgim-acts") if r["type"] == "movement"]
    expected = np.array([r["outcome"] if r["outcome"] is not None else [np.nan] * 2
                         for r in moves], dtype=float)
    assert np.array_equal(values["outcome"], expected, equal_nan=True)
    assert len(values["count"]) == len(values["value"]) == len(values["own"]) > 10
    run = SimpleNamespace(name="moved", outcome=expected.copy())
    acts_values.check_same_run(values, run)
    run.outcome[17, 0] += 1e-12
    with pytest.raises(acts_values.ReplayMismatch, match="movement 18 is not the run's"):
        acts_values.check_same_run(values, run)


def test_a_region_first_gain_choice_asks_only_where_its_own_gain_is_lower():
    """(A)+(B) takes the pair of largest gain / cost in the goal's leaf: a teacher (cost 5 or
    10) is asked only where the learner's own gain is at most a fifth of the asking pair's."""
    name = "sgim-acts-strategy_choice_order=region-first-strategy_value=gain-seed0"
    values = acts_values.replay(short(name))
    social = np.char.find(values["strategy"], ":") >= 0
    assert social.any() and (~social).any()
    assert np.all(values["own"][social] <= values["value"][social] / 5 + 1e-12)
    autonomous = ~social
    assert np.array_equal(values["own"][autonomous], values["value"][autonomous])
