"""Local linear models: exact on a linear world, noise averaged, never across neighbourhoods."""

import numpy as np
import pytest

from sgim_nodes.core import local_model
from sgim_nodes.core.memory import Memory

J_TRUE = np.array([[0.5, -0.2, 0.1, 0.0], [0.1, 0.3, 0.0, -0.4]])


def _memory(points, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    mem = Memory(4, 2)
    for a in points:
        mem.add(a, J_TRUE @ a + rng.normal(0, noise, 2))
    return mem


def test_exact_on_a_linear_world():
    rng = np.random.default_rng(1)
    centre = np.full(4, 0.2)
    mem = _memory(centre + rng.uniform(-0.1, 0.1, (40, 4)))
    fit = local_model.fit(mem, centre, radius=0.5, max_pairs=60)
    assert fit.outcome == pytest.approx(J_TRUE @ centre, abs=1e-3)
    assert fit.jacobian == pytest.approx(J_TRUE, abs=0.02)
    goal = J_TRUE @ centre + np.array([0.02, -0.01])
    action, predicted = local_model.step(fit, goal, radius=1.0)
    assert J_TRUE @ action == pytest.approx(goal, abs=1e-3) and predicted == pytest.approx(goal,
                                                                                          abs=1e-3)


def test_the_prediction_averages_the_noise_of_nearby_casts():
    rng = np.random.default_rng(2)
    errors_fit, errors_single = [], []
    for seed in range(30):
        centre = rng.uniform(-0.5, 0.5, 4)
        mem = _memory(centre + rng.uniform(-0.05, 0.05, (30, 4)), noise=0.05, seed=seed)
        fit = local_model.fit(mem, mem.actions[0], radius=0.3, max_pairs=60)
        truth = J_TRUE @ mem.actions[0]
        errors_fit.append(np.linalg.norm(fit.outcome - truth))
        errors_single.append(np.linalg.norm(mem.outcomes[0] - truth))
    assert np.mean(errors_fit) < 0.5 * np.mean(errors_single)


def test_far_pairs_are_not_used():
    mem = _memory([np.zeros(4), np.full(4, 0.01), np.full(4, -0.01), np.ones(4), -np.ones(4)])
    assert local_model.fit(mem, np.full(4, 0.5), radius=0.1, max_pairs=60) is None
    fit = local_model.fit(mem, np.zeros(4), radius=0.1, max_pairs=60)
    assert fit is not None and fit.n_effective <= 3.0


def test_step_stays_within_its_radius_and_the_box():
    rng = np.random.default_rng(3)
    centre = np.full(4, 0.95)
    mem = _memory(centre - rng.uniform(0, 0.05, (30, 4)))
    fit = local_model.fit(mem, centre, radius=0.5, max_pairs=60)
    action, _ = local_model.step(fit, np.array([5.0, 5.0]), radius=0.1)
    assert np.linalg.norm(action - centre) <= 0.1 + 1e-12 and np.all(np.abs(action) <= 1.0)
