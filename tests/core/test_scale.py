"""A world's declared scale, and the configuration's relative distances in its units."""

import math

import numpy as np
import pytest

from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.planar_arm import ARMS, PlanarArm
from sgim_nodes.core.scale import WorldScale, gaussian_noise_2d, unit_box


def test_gaussian_noise_measure_matches_the_papers_protocol():
    # the paper's measure: mean distance of repeated outcomes to their mean
    rng = np.random.default_rng(0)
    casts = rng.normal(0.0, 0.03, (20000, 10, 2))
    measured = np.linalg.norm(casts - casts.mean(1, keepdims=True), axis=2).mean()
    # the sample mean of 10 casts removes 1/10 of the variance
    assert measured == pytest.approx(gaussian_noise_2d(0.03) * math.sqrt(0.9), rel=0.02)


def test_box_geometry_and_refusals():
    s = WorldScale((-0.4, -0.9), (1.1, 0.9), 0.025)
    assert s.size == pytest.approx(1.8) and s.diagonal == pytest.approx(math.hypot(1.5, 1.8))
    assert s.centre == pytest.approx([0.35, 0.0])
    assert s.contains(np.array([1.1, 0.0])) and not s.contains(np.array([1.2, 0.0]))
    assert unit_box(2, 0.07).size == 2.0
    for bad in [((0.0,), (0.0,), 0.1), ((0.0,), (1.0,), 0.0), ((0.0, 0.0), (1.0,), 0.1),
                ((0.0,), (math.inf,), 0.1), ((0.0,), (1.0,), math.nan)]:
        with pytest.raises(ValueError):
            WorldScale(*bad)


def test_the_same_config_scales_with_each_world():
    c = LearnerConfig()
    fishing, arm = unit_box(2, 0.07), ARMS["arm-20"].make(0).scale
    d_f, d_a = c.distances(fishing), c.distances(arm)
    assert d_f.reach_threshold == pytest.approx(c.reach_threshold_noise * 0.07)
    assert d_a.reach_threshold == pytest.approx(c.reach_threshold_noise * arm.noise)
    assert d_f.min_region_width == pytest.approx(c.min_region_width_size * 2.0)
    assert d_a.min_region_width == pytest.approx(c.min_region_width_size * 1.8)
    # doubling a world's noise doubles every noise-relative distance, nothing else
    loud = c.distances(unit_box(2, 0.14))
    assert loud.mode3_radius == pytest.approx(2 * d_f.mode3_radius)
    assert loud.min_region_width == d_f.min_region_width


def test_arms_declare_their_noise_the_papers_way():
    assert PlanarArm(noise=0.02).scale.noise == pytest.approx(gaussian_noise_2d(0.02))
    assert PlanarArm().scale.noise > 0  # a noise-free arm still declares a resolution
    arm = ARMS["arm-20"].make(0)
    assert arm.scale.low == (-0.4, -0.9) and arm.scale.high == (1.1, 0.9)
    outcome = arm.execute(np.ones(20)).outcome
    assert arm.scale.contains(outcome)
