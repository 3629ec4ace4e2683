"""Stored data files load with the right shapes, and the benchmark set regenerates exactly."""

import numpy as np

from sim_bridge.data_files import (
    load_benchmark_goals,
    load_reachable_casts,
    load_teaching_set,
)
from sim_bridge.tools.make_benchmark_set import benchmark_goals


def test_benchmark_goals_shape() -> None:
    goals = load_benchmark_goals()
    assert goals.ndim == 2 and goals.shape[1] == 2
    assert 60 <= len(goals) <= 26 * 16
    assert np.all(np.abs(goals) <= 1.0)


def test_benchmark_set_regenerates_exactly_from_the_map() -> None:
    stored = np.load(load_benchmark_goals.__globals__["_path"]("benchmark_goals.npz", None))
    regenerated = benchmark_goals(load_reachable_casts().outcomes, int(stored["seed"]))
    assert regenerated.tobytes() == stored["goals"].tobytes()


def test_teaching_set_shapes() -> None:
    t = load_teaching_set()
    m = len(t.actions)
    assert 10 <= m <= 60
    assert t.actions.shape == (m, 24) and t.outcomes.shape == (m, 2) and t.spread.shape == (m,)
    assert np.all(np.abs(t.actions) <= 1.0) and np.all(t.spread >= 0)


def test_reachable_map_shapes() -> None:
    casts = load_reachable_casts()
    assert casts.actions.shape[1] == 24 and casts.outcomes.shape == (len(casts.actions), 2)
