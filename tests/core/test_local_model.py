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


def _line_of_casts():
    """Casts spread +-0.1 along the first action axis, +-0.01 along the second, none along
    the others; a radius so large that every weight is about 1."""
    offsets = [t * np.eye(4)[0] + u * np.eye(4)[1] for t in (-0.1, -0.05, 0.05, 0.1)
               for u in (-0.01, 0.01)]
    mem = _memory(offsets)
    return local_model.fit(mem, np.zeros(4), radius=100.0, max_pairs=60)


def test_the_spread_along_a_direction_is_the_rms_offset_of_the_casts_that_way():
    fit = _line_of_casts()
    axis0, axis1, diagonal = np.eye(4)[0], np.eye(4)[1], np.array([1.0, 1.0, 0, 0]) / np.sqrt(2)
    assert fit.spread_along(axis0) == pytest.approx(np.sqrt((0.1**2 + 0.05**2) / 2), rel=1e-4)
    assert fit.spread_along(axis1) == pytest.approx(0.01, rel=1e-4)
    assert fit.spread_along(np.eye(4)[3]) == pytest.approx(0.0, abs=1e-12)
    # Offsets along axis 0 and axis 1 are uncorrelated: the squares add, halved.
    assert fit.spread_along(diagonal) == pytest.approx(
        np.sqrt((fit.spread_along(axis0) ** 2 + 0.01**2) / 2), rel=1e-4)


def test_a_supported_step_goes_no_farther_than_its_casts_and_keeps_its_direction():
    fit = _line_of_casts()
    goal = fit.outcome + np.array([1.0, 0.5])  # far: every bound binds
    free, _ = local_model.step(fit, goal, radius=0.5)
    bounded, predicted = local_model.step(fit, goal, radius=0.5, support=2.0)
    assert np.linalg.norm(free) == pytest.approx(0.5)
    direction = bounded / np.linalg.norm(bounded)
    assert np.linalg.norm(bounded) == pytest.approx(2.0 * fit.spread_along(direction))
    assert direction == pytest.approx(free / np.linalg.norm(free))
    assert predicted == pytest.approx(fit.outcome + fit.jacobian @ bounded)
    # A goal within the casts' reach: the bound does not bind, the step is the free one.
    near = fit.outcome + 0.2 * fit.jacobian @ (0.05 * np.eye(4)[0])
    assert local_model.step(fit, near, 0.5, 2.0)[0] == pytest.approx(
        local_model.step(fit, near, 0.5)[0])


def _reference_loo(memory, centre, radius, max_pairs):
    """Leave-one-out by refitting: each pair dropped in turn, the others refitted with the same
    weights and ridge, the dropped pair predicted."""
    dist, idx = memory.nearest_actions(centre, max_pairs)
    keep = dist <= radius
    dist, idx = dist[keep], idx[keep]
    x, y = memory.actions[idx] - centre, memory.outcomes[idx]
    w = np.exp(-0.5 * (dist / (0.5 * radius)) ** 2)
    lam = local_model.RIDGE * float((w[:, None] * x**2).sum() / w.sum())
    design = np.hstack([np.ones((len(idx), 1)), x])
    errors = []
    for i in range(len(idx)):
        rest = np.arange(len(idx)) != i
        a = design[rest] * w[rest, None]
        gram = design[rest].T @ a + np.diag(np.r_[0.0, np.full(x.shape[1], lam)])
        beta = np.linalg.solve(gram, a.T @ y[rest])
        errors.append(y[i] - design[i] @ beta)
    errors = np.array(errors)
    return float(np.sqrt((w * (errors**2).sum(1)).sum() / w.sum()))


def test_held_out_error_is_the_leave_one_out_error_of_refits():
    rng = np.random.default_rng(3)
    mem = Memory(3, 2)
    for _ in range(15):
        a = rng.uniform(-0.3, 0.3, 3)
        mem.add(a, np.array([a[0] + a[1] ** 2, a[2] - a[0]]) + rng.normal(0, 0.02, 2))
    centre = mem.actions[0]
    fit = local_model.fit(mem, centre, radius=0.6, max_pairs=60)
    assert fit.held_out == pytest.approx(_reference_loo(mem, centre, 0.6, 60), rel=1e-9)
    assert fit.held_out > fit.residual  # a held-out cast is harder to predict than a seen one


def test_misfit_is_what_the_model_gets_wrong_beyond_the_worlds_noise():
    """A linear world with noise: the held-out error is about the noise, the misfit small. A
    world that changes faster than the neighbourhood (a chaotic one, as a cast's landing can
    be): the misfit is far larger than the noise."""
    rng = np.random.default_rng(4)
    sigma = 0.02
    noise_rms = sigma * np.sqrt(2.0)
    smooth, rough = Memory(4, 2), Memory(4, 2)
    for _ in range(200):
        a = rng.uniform(-0.5, 0.5, 4)
        smooth.add(a, np.array([a[0] + 0.5 * a[1], a[2] - a[3]]) + rng.normal(0, sigma, 2))
        rough.add(a, 0.3 * np.sin(40.0 * a[:2]) + rng.normal(0, sigma, 2))
    centre = np.zeros(4)
    smooth_fit = local_model.fit(smooth, centre, radius=0.8, max_pairs=60)
    rough_fit = local_model.fit(rough, centre, radius=0.8, max_pairs=60)
    assert smooth_fit.misfit(noise_rms) < 0.5 * noise_rms
    assert rough_fit.misfit(noise_rms) > 5.0 * noise_rms
    assert smooth_fit.misfit(10.0) == 0.0  # never negative
