"""Stored data files: shapes and documented sizes, the benchmark set regenerates exactly, and the
teaching set holds a demonstration in the isolated pond that lands there when replayed."""

import os

import numpy as np

from sim_bridge.data_files import (
    BENCHMARK_GOALS,
    REACHABLE_MAP,
    data_dir,
    in_isolated_region,
    load_benchmark_goals,
    load_reachable_casts,
    load_teaching_set,
)
from sim_bridge.fishing_world import FishingWorld, Status
from sim_bridge.tools.make_benchmark_set import benchmark_goals


def test_benchmark_goals_within_documented_bounds() -> None:
    """README_world.md: on the order of the paper's 129, documented bounds 90-180."""
    goals = load_benchmark_goals()
    assert goals.ndim == 2 and goals.shape[1] == 2
    assert 90 <= len(goals) <= 180
    assert np.all(np.abs(goals) <= 1.0)


def test_benchmark_set_regenerates_exactly_from_the_map() -> None:
    with np.load(data_dir() / BENCHMARK_GOALS) as stored:
        regenerated = benchmark_goals(load_reachable_casts().outcomes, int(stored["seed"]))
        assert regenerated.tobytes() == stored["goals"].tobytes()


def test_teaching_set_within_documented_bounds() -> None:
    """README_world.md: on the order of the paper's 27, documented bounds 20-35."""
    t = load_teaching_set()
    m = len(t.actions)
    assert 20 <= m <= 35
    assert t.actions.shape == (m, 24) and t.outcomes.shape == (m, 2) and t.spread.shape == (m,)
    assert np.all(np.abs(t.actions) <= 1.0) and np.all(t.spread >= 0)


def test_teaching_entry_in_the_isolated_pond_lands_there() -> None:
    t = load_teaching_set()
    pond = np.flatnonzero(in_isolated_region(t.outcomes))
    assert len(pond) >= 1
    with FishingWorld(seed=0, noise=0.0) as w:
        for i in pond:
            r = w.execute(t.actions[i])
            assert r.status == Status.OK
            assert in_isolated_region(r.outcome)
            assert np.linalg.norm(r.outcome - t.outcomes[i]) < 3 * t.spread[i] + 0.02


def test_reachable_map_shapes_size_and_cover() -> None:
    casts = load_reachable_casts()
    n = len(casts.actions)
    assert casts.actions.shape == (n, 24) and casts.outcomes.shape == (n, 2)
    assert os.path.getsize(data_dir() / REACHABLE_MAP) < 3e6
    # The mapping reaches every part of the water: its points span the outcome box.
    lo, hi = casts.outcomes.min(axis=0), casts.outcomes.max(axis=0)
    assert np.all(lo < -0.93) and np.all(hi > 0.93)
    assert in_isolated_region(casts.outcomes).sum() >= 50
