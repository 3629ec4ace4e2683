"""Similarity and competence against hand-computed values."""

import math

import numpy as np
import pytest

from sgim_nodes.core.competence import (
    competence,
    origin_vector,
    rescaled_distance,
    similarity,
)

ORIGIN = np.zeros(2)


def test_rescaled_distance_spans_zero_to_one():
    assert rescaled_distance(np.array([-1.0, -1.0]), np.array([1.0, 1.0])) == pytest.approx(1.0)
    # 0.5 / (2 * sqrt(2))
    expected = 0.5 / (2 * math.sqrt(2))
    assert rescaled_distance(np.array([0.5, 0.0]), ORIGIN) == pytest.approx(expected)


def test_similarity_hand_values():
    g = np.array([0.5, 0.0])
    assert similarity(g, np.array([0.25, 0.0]), ORIGIN) == pytest.approx(-0.5)
    assert similarity(g, np.array([0.5, 0.3]), ORIGIN) == pytest.approx(-0.6)  # 0.3 / 0.5
    assert similarity(g, np.array([-1.0, 0.0]), ORIGIN) == -1.0  # ratio 3, capped at 1
    assert similarity(g, g, ORIGIN) == 0.0


def test_similarity_goal_at_origin():
    assert similarity(ORIGIN, ORIGIN, ORIGIN) == 0.0
    assert similarity(ORIGIN, np.array([0.01, 0.0]), ORIGIN) == -1.0


def test_competence_threshold():
    g = np.array([0.5, 0.0])
    # Sim = -0.5 <= eps -> competence = Sim
    assert competence(g, np.array([0.25, 0.0]), ORIGIN, eps_sim=-0.05) == pytest.approx(-0.5)
    # Sim = -0.02 > eps = -0.05 -> 0 (counted as a full success)
    assert competence(g, np.array([0.49, 0.0]), ORIGIN, eps_sim=-0.05) == 0.0
    # Sim exactly at eps -> Sim (the formula uses <=)
    y = np.array([0.45, 0.0])
    sim = similarity(g, y, ORIGIN)
    assert sim == pytest.approx(-0.1)
    assert competence(g, y, ORIGIN, eps_sim=sim) == sim
    assert competence(g, y, ORIGIN, eps_sim=sim - 1e-9) == 0.0
    # with eps_sim = 0 competence is Sim itself
    assert competence(g, np.array([0.49, 0.0]), ORIGIN, eps_sim=0.0) == pytest.approx(-0.02)


def test_origin_vector():
    assert np.array_equal(origin_vector(None, 2), [0.0, 0.0])
    assert np.array_equal(origin_vector((0.5, -0.5), 2), [0.5, -0.5])
    with pytest.raises(ValueError):
        origin_vector((0.5,), 2)
