"""Competence against memory: hand values, and the constants that keep the interest clean."""

import numpy as np
import pytest

from sgim_nodes.core.competence import competence, start_distance

G = np.array([0.5, 0.0])
TOL = 0.05


def _at(d):
    return G + np.array([0.0, d])


def test_hand_values():
    # memory was 0.45 away (0.40 beyond the tolerance); the attempt reached 0.25 (0.20 beyond)
    assert competence(G, _at(0.25), 0.45, TOL) == pytest.approx(-0.5)
    assert competence(G, _at(0.05), 0.45, TOL) == 0.0  # within the tolerance: a full success
    assert competence(G, _at(0.0), 0.45, TOL) == 0.0
    assert competence(G, None, 0.45, TOL) == -1.0  # every movement failed


def test_no_gain_on_memory_is_exactly_minus_one_wherever_the_goal_lies():
    # an unreachable goal: the attempt lands no closer than memory already did
    for d0 in (0.11, 0.3, 0.9):
        for extra in (0.0, 0.01, 0.5):
            assert competence(G, _at(d0 + extra), d0, TOL) == -1.0


def test_a_goal_memory_already_reaches_is_judged_on_the_tolerance():
    assert competence(G, _at(0.04), 0.01, TOL) == 0.0
    assert competence(G, _at(0.075), 0.01, TOL) == pytest.approx(-0.5)  # 0.025 beyond, / 0.05
    assert competence(G, _at(0.2), 0.01, TOL) == -1.0


def test_start_distance_without_memory_is_the_distance_to_the_centre():
    assert start_distance(0.3, G, np.zeros(2)) == 0.3
    assert start_distance(float("inf"), G, np.zeros(2)) == pytest.approx(0.5)


def test_a_floor_keeps_a_noise_sized_miss_from_counting_as_total_failure():
    # memory 0.01 away: 0.075 is 0.025 beyond the tolerance, over a floor of 0.2 (not 0.05)
    assert competence(G, _at(0.075), 0.01, TOL, floor=0.2) == pytest.approx(-0.125)
    # a far goal is untouched by the floor: no gain on memory is still exactly -1
    assert competence(G, _at(0.5), 0.5, TOL, floor=0.2) == -1.0
    assert competence(G, _at(0.25), 0.45, TOL, floor=0.2) == pytest.approx(-0.5)
