"""The isolated pond's size as a parameter of the world (``lake.Lake``); the default unchanged."""

import numpy as np
import pytest

from sim_bridge import lake, scaling
from sim_bridge.data_files import (
    ISOLATED_REGION,
    in_isolated_region,
    isolated_region,
    load_reachable_casts,
)
from sim_bridge.fishing_world import FishingWorld, Status
from sim_bridge.lake import Lake

SMALL = lake.POND[2] / 2  # m


def test_default_lake_is_the_documented_world() -> None:
    assert Lake().pond == lake.POND == (-7.225, -2.125, 0.75)
    assert Lake().is_default and not Lake(pond_radius=SMALL).is_default
    assert lake.lake_with_pond_radius(None) is lake.DEFAULT_LAKE
    np.testing.assert_allclose(ISOLATED_REGION["centre"], (-0.85, -0.25), atol=1e-12)
    assert ISOLATED_REGION["radius"] == pytest.approx(0.75 * 2 / 17)
    assert isolated_region() == ISOLATED_REGION == Lake().isolated_region()
    g = np.random.default_rng(0).uniform(-9, 9, (20000, 2))
    assert np.array_equal(lake.water_body(g), Lake().water_body(g))
    with FishingWorld(seed=0) as w:
        assert w.lake is lake.DEFAULT_LAKE


def test_smaller_pond_same_place_land_around() -> None:
    small = Lake(pond_radius=SMALL)
    reg = small.isolated_region()
    assert reg["centre"] == ISOLATED_REGION["centre"]
    assert reg["radius"] == pytest.approx(ISOLATED_REGION["radius"] / 2)
    cx, cy, _ = lake.POND
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    ring = np.c_[np.cos(t), np.sin(t)]
    assert np.all(small.water_body(np.array([cx, cy]) + 0.98 * SMALL * ring) == lake.ISOLATED_POND)
    for d in np.linspace(1.02 * SMALL, lake.POND[2] + 1.3, 30):  # the rest of the pond is land
        assert np.all(small.water_body(np.array([cx, cy]) + d * ring) == lake.LAND)
    # the main lake is untouched
    pts = np.random.default_rng(1).uniform(-9, 9, (20000, 2))
    far = np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) > lake.POND[2] + 0.05
    assert np.array_equal(small.water_body(pts[far]), lake.water_body(pts[far]))
    u = np.array(reg["centre"]) + 0.98 * reg["radius"] * ring
    assert np.all(small.in_isolated_region(u))
    assert not np.any(small.in_isolated_region(np.array(reg["centre"]) + 1.02 * reg["radius"]
                                               * ring))
    assert np.all(in_isolated_region(u))  # inside the default pond too


@pytest.mark.parametrize("kw", [{"pond_radius": 0.0}, {"pond_radius": -1.0},
                                {"pond_radius": float("nan")}, {"pond_radius": 3.0},
                                {"pond_centre": (1.0, 0.3)}, {"pond_centre": (-8.4, -8.4)}])
def test_bad_ponds_are_refused(kw: dict) -> None:
    with pytest.raises(ValueError):
        Lake(**kw)


def test_smaller_pond_is_hit_by_fewer_random_casts() -> None:
    """The mapped landings (random, spread and pond phases) and a replay of mapped pond casts:
    the physics is the same, only fewer of them land on water."""
    small = Lake(pond_radius=SMALL)
    mapped = load_reachable_casts().outcomes.astype(float)
    n_default = int(in_isolated_region(mapped).sum())
    n_small = int(small.in_isolated_region(mapped).sum())
    assert 0 < n_small < n_default
    kept = load_reachable_casts(lake=small)
    assert small.in_isolated_region(kept.outcomes).sum() == n_small
    assert not np.any(in_isolated_region(kept.outcomes) & ~small.in_isolated_region(
        kept.outcomes))  # the default pond's other landings are on land now: dropped
    casts = load_reachable_casts()
    pond = np.flatnonzero(in_isolated_region(casts.outcomes))[:40]
    hits = {"default": 0, "small": 0}
    with FishingWorld(seed=3) as wd, FishingWorld(seed=3, lake=small) as ws:
        assert ws.lake is small
        for a in casts.actions[pond].astype(float):
            rd, rs = wd.execute(a), ws.execute(a)
            np.testing.assert_array_equal(rd.world_point, rs.world_point)  # same physics
            in_small = small.water_body(rs.world_point) == lake.ISOLATED_POND
            assert (rs.status == Status.OK) == bool(small.is_water(rs.world_point))
            if in_small:
                np.testing.assert_array_equal(rs.outcome,
                                              scaling.world_to_outcome(rs.world_point))
            hits["default"] += lake.water_body(rd.world_point) == lake.ISOLATED_POND
            hits["small"] += bool(in_small)
    assert 0 <= hits["small"] < hits["default"]


def test_runner_builds_the_world_with_the_pond() -> None:
    from sgim_nodes.core.runner import build_world, parse_args

    w = build_world("fishing", 0, pond_radius=SMALL)
    assert w.env.lake.pond[2] == SMALL and w.eval_env.lake.pond[2] == SMALL
    d = build_world("fishing", 0)
    assert d.env.lake is lake.DEFAULT_LAKE
    for x in (w.env, w.eval_env, d.env, d.eval_env):
        x.close()
    with pytest.raises(ValueError):
        build_world("planar-arm", 0, pond_radius=SMALL)
    assert parse_args(["--output", "x.jsonl"]).pond_radius is None
    with pytest.raises(SystemExit):
        parse_args(["--output", "x.jsonl", "--pond-radius", "0.3"])  # planar arm has no pond
