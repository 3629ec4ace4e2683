"""Stored data files: documented sizes; every benchmark goal and teaching outcome on reached
water; the isolated region demonstrated and sampled; the tools regenerate the files exactly; the
floor matches the benchmark goals."""

import os

import numpy as np
import pytest

from sim_bridge import scaling
from sim_bridge.data_files import (
    BENCHMARK_FLOOR,
    BENCHMARK_GOALS,
    REACHABLE_MAP,
    TEACHING_SET,
    data_dir,
    in_isolated_region,
    load_benchmark_goals,
    load_floor,
    load_reachable_casts,
    load_teaching_set,
)
from sim_bridge.fishing_world import FishingWorld, Status
from sim_bridge.lake import is_water
from sim_bridge.tools import make_floor, make_teaching_set
from sim_bridge.tools.make_benchmark_set import (
    GRID,
    benchmark_goals,
    grid_cells,
    on_reached_water,
    validation_goals,
)
from sim_bridge.tools.map_reachable import run_mapping


@pytest.fixture(scope="module")
def casts():
    return load_reachable_casts()


def _stored(name: str) -> dict:
    with np.load(data_dir() / name) as f:
        return {k: f[k] for k in f.files}


def test_reachable_map_shapes_size_and_cover(casts) -> None:
    n = len(casts.actions)
    assert n >= 10_000
    assert casts.actions.shape == (n, 24) and casts.outcomes.shape == (n, 2)
    assert np.all(np.abs(casts.actions) <= 1.0)
    assert os.path.getsize(data_dir() / REACHABLE_MAP) < 1e6  # shipped: small enough for git
    # The mapping reaches every part of the water: its points span the outcome box.
    lo, hi = casts.outcomes.min(axis=0), casts.outcomes.max(axis=0)
    assert np.all(lo < -0.93) and np.all(hi > 0.93)
    assert np.all(is_water(scaling.outcome_to_world(casts.outcomes.astype(float))))
    assert in_isolated_region(casts.outcomes).sum() >= 50


def test_the_mapping_tool_made_the_stored_map(casts) -> None:
    """The map is a function of its seed: the tool's first 60 random casts give exactly the
    stored map's first landings (the rest follows the same code; rerunning all of it takes
    minutes: README_world.md gives the command)."""
    stored = _stored(REACHABLE_MAP)
    actions, outcomes, _ = run_mapping(60, 0, int(stored["seed"]), progress=False)
    n = len(outcomes)
    assert n > 20
    assert outcomes.tobytes() == casts.outcomes[:n].tobytes()
    q = np.round(actions * stored["action_scale"]).astype(np.int16)
    assert q.tobytes() == stored["actions"][:n].tobytes()


def test_benchmark_goals_on_reached_water_and_in_the_isolated_region(casts) -> None:
    """README_world.md: the paper's 129 (bounds 90-180), all on reached water, some in the
    isolated region (the benchmark samples it)."""
    goals = load_benchmark_goals()
    assert goals.ndim == 2 and goals.shape[1] == 2
    assert 90 <= len(goals) <= 180
    assert np.all(on_reached_water(goals, casts.outcomes.astype(float)))
    assert in_isolated_region(goals).sum() >= 1


def test_benchmark_set_regenerates_exactly_from_the_map(casts) -> None:
    stored = _stored(BENCHMARK_GOALS)
    regenerated = benchmark_goals(casts.outcomes, int(stored["seed"]))
    assert regenerated.tobytes() == stored["goals"].tobytes()


def test_validation_goals_are_other_points_of_the_benchmarks_cells(casts) -> None:
    """Fishing's validation goals (choices are judged on them, never on the benchmark): one in
    each cell the benchmark samples, on reached water too, and none of them a benchmark goal."""
    reached = casts.outcomes.astype(float)
    goals, validation = load_benchmark_goals(), validation_goals(reached)
    lo, size, _ = grid_cells(reached)

    def cells(points: np.ndarray) -> list[tuple[int, int]]:
        index = np.minimum(np.floor((points - lo) / size).astype(int), np.array(GRID) - 1)
        return [tuple(c) for c in index.tolist()]

    assert validation.shape == goals.shape
    assert np.all(on_reached_water(validation, reached))
    assert sorted(cells(validation)) == sorted(cells(goals))
    assert np.min(np.linalg.norm(validation[:, None] - goals[None], axis=2)) > 0


def test_teaching_set_within_bounds_on_reached_water(casts) -> None:
    """README_world.md: on the order of the paper's 27 (bounds 20-35), exactly one entry in
    the isolated region, every demonstrated outcome on reached water."""
    t = load_teaching_set()
    m = len(t.actions)
    assert 20 <= m <= 35
    assert t.actions.shape == (m, 24) and t.outcomes.shape == (m, 2) and t.spread.shape == (m,)
    assert np.all(np.abs(t.actions) <= 1.0) and np.all(t.spread >= 0)
    assert np.all(on_reached_water(t.outcomes, casts.outcomes.astype(float)))
    assert in_isolated_region(t.outcomes).sum() == 1


def test_teaching_entry_in_the_isolated_region_lands_there() -> None:
    t = load_teaching_set()
    [i] = np.flatnonzero(in_isolated_region(t.outcomes))
    with FishingWorld(seed=0, noise=0.0) as w:
        r = w.execute(t.actions[i])
    assert r.status == Status.OK and in_isolated_region(r.outcome)
    assert np.linalg.norm(r.outcome - t.outcomes[i]) < 3 * t.spread[i] + 0.02
    with FishingWorld(seed=11) as w:  # and with the world's noise, cast after cast
        results = [w.execute(t.actions[i]) for _ in range(5)]
    assert sum(r.status == Status.OK and bool(in_isolated_region(r.outcome))
               for r in results) >= 4


def test_teaching_entries_regenerate_exactly(casts) -> None:
    """Each group has its own random stream: the isolated region's entry and another one,
    rebuilt alone from the map, equal the stored entries bit for bit."""
    stored = _stored(TEACHING_SET)
    grid = tuple(int(v) for v in stored["grid"])
    pond_group = grid[0] * grid[1]
    groups = [pond_group, int(stored["group"][len(stored["group"]) // 2])]
    a, o, s, g = make_teaching_set.teaching_set(
        casts.actions, casts.outcomes, grid, int(stored["candidates"]), int(stored["repeats"]),
        int(stored["seed"]), int(stored["max_candidates"]), progress=False, groups=groups)
    for k, group in enumerate(g):
        [i] = np.flatnonzero(stored["group"] == group)
        assert a[k].tobytes() == stored["actions"][i].tobytes()
        assert o[k].tobytes() == stored["outcomes"][i].tobytes()
        assert s[k] == stored["spread"][i]
    assert sorted(g.tolist()) == sorted(groups)


def test_floor_matches_the_benchmark_set() -> None:
    floor, goals = load_floor(), load_benchmark_goals()
    assert floor.goals.tobytes() == goals.tobytes()  # same goals, same order
    assert floor.per_goal.shape == floor.nearest.shape == (len(goals),)
    assert np.all(floor.per_goal > 0) and np.all(np.isfinite(floor.per_goal))
    assert floor.k >= 2 and floor.choose_casts >= 1 and floor.score_casts >= 1
    # choosing among k neighbours on some casts helps on held-back casts, on average
    assert floor.mean < floor.nearest_mean
    assert floor.mean == pytest.approx(float(np.mean(floor.per_goal)))


@pytest.mark.slow
def test_floor_regenerates_exactly_for_some_goals(casts) -> None:
    stored, goals = _stored(BENCHMARK_FLOOR), load_benchmark_goals()
    pond = int(np.flatnonzero(in_isolated_region(goals))[0])
    rows = [0, pond, len(goals) - 1]
    f = make_floor.floor(goals, casts.actions, casts.outcomes, int(stored["k"]),
                         int(stored["choose_casts"]), int(stored["score_casts"]),
                         int(stored["seed"]), indices=rows, progress=False)
    assert f["best"].tobytes() == stored["per_goal"][rows].tobytes()
    assert f["nearest"].tobytes() == stored["nearest"][rows].tobytes()
    assert f["neighbours"].tobytes() == stored["neighbours"][rows].tobytes()
