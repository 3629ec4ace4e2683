"""Reliability, variance and Gaussian interpolation weights against hand values."""

import math

import numpy as np
import pytest

from sgim_nodes.core.inverse_model import (
    InverseModel,
    action_variance,
    gaussian_weights,
    reliability,
)
from sgim_nodes.core.memory import Memory


def test_formulas_hand_values():
    # mean [0.5, 0.5]; squared distances 0.5 each; / dim 2 -> 0.25
    assert action_variance(np.array([[0.0, 0.0], [1.0, 1.0]])) == pytest.approx(0.25)
    assert reliability(0.1, 0.25, 0.5) == pytest.approx(0.225)
    e = math.exp(-0.5)  # distance sigma -> exp(-1/2)
    assert gaussian_weights(np.array([0.0, 0.05]), 0.05) == pytest.approx([1 / (1 + e),
                                                                           e / (1 + e)])
    # far distances do not underflow: only differences matter
    w = gaussian_weights(np.array([10.0, 10.0]), 0.01)
    assert w == pytest.approx([0.5, 0.5])


def _memory():
    mem = Memory(1, 2)
    # A and B: nearly the same outcome from opposite actions (redundant, unreliable)
    mem.add(np.array([-1.0]), np.array([0.0, 0.0]))  # A, index 0
    mem.add(np.array([1.0]), np.array([0.01, 0.0]))  # B, index 1
    # C and D: consistent neighbourhood farther from the goal
    mem.add(np.array([0.5]), np.array([0.3, 0.0]))  # C, index 2
    mem.add(np.array([0.52]), np.array([0.32, 0.0]))  # D, index 3
    return mem


def test_most_reliable_candidate_and_interpolation():
    mem = _memory()
    model = InverseModel(mem, l_max=3, k_max=2, alpha=0.5, sigma=0.05)
    est = model.estimate(np.array([0.1, 0.0]))
    # candidates: B (0.09, var 1 -> 0.59), A (0.1, var 1 -> 0.6), C (0.2, var 1e-4 -> 0.20005)
    assert est.candidate_index == 2
    assert est.reliability == pytest.approx(0.2 + 0.5 * 0.0001)
    assert sorted(est.neighbour_indices.tolist()) == [2, 3]
    # weights of C (d=0.2) and D (d=0.22): exp(-(0.22^2 - 0.2^2) / (2 * 0.05^2))
    w_d = math.exp(-(0.22**2 - 0.2**2) / (2 * 0.05**2))
    expected = (0.5 + 0.52 * w_d) / (1 + w_d)
    assert est.action == pytest.approx([expected])


def test_alpha_zero_picks_the_nearest_candidate():
    mem = _memory()
    model = InverseModel(mem, l_max=3, k_max=2, alpha=0.0, sigma=0.05)
    est = model.estimate(np.array([0.1, 0.0]))
    assert est.candidate_index == 1  # B is the closest to the goal


def test_empty_memory_gives_none():
    assert InverseModel(Memory(1, 2), 3, 2, 0.5, 0.05).estimate(np.zeros(2)) is None
