"""The refinement optimisers on a linear world with noise: each gains on its start."""

import numpy as np
import pytest

from sgim_nodes.core.memory import Memory
from sgim_nodes.core.refinement import (
    NelderMeadSearch,
    ProbeScale,
    RandomSearch,
    SubspaceSearch,
)

rng0 = np.random.default_rng(0)
J = rng0.normal(0, 0.3, (2, 12))


def world(a, rng, noise):
    return J @ np.asarray(a) + rng.normal(0, noise, 2)


def _drive(search, goal, start, rng, noise, budget=10):
    costs = []
    for _ in range(budget - 1):
        a = search.ask()
        assert a.shape == start.shape and np.all(np.abs(a) <= 1)
        y = world(a, rng, noise)
        cost = float(np.linalg.norm(y - goal))
        if isinstance(search, SubspaceSearch):
            search.tell_outcome(a, y, cost)
        else:
            search.tell(a, cost)
        costs.append(float(np.linalg.norm(J @ a - goal)))  # the true error of each cast
    return costs


def test_subspace_search_reaches_a_goal_the_start_misses():
    true_errors = []
    for seed in range(20):
        rng = np.random.default_rng(seed)
        start = rng.uniform(-0.3, 0.3, 12)
        goal = J @ start + rng.normal(0, 0.15, 2)  # 0.15 away: 7 noise units
        y0 = world(start, rng, 0.02)
        s = SubspaceSearch(goal, start, y0, float(np.linalg.norm(y0 - goal)), probe=0.4,
                           n_probes=2, rng=rng)
        costs = _drive(s, goal, start, rng, 0.02)
        true_errors.append(costs[-1])
    assert np.median(true_errors) < 0.05  # from ~0.19 to within ~2 noise units


def test_subspace_search_without_outcomes_keeps_probing_inside_the_box():
    rng = np.random.default_rng(1)
    start = np.full(12, 0.99)
    s = SubspaceSearch(np.zeros(2), start, None, 2.0, probe=0.5, n_probes=2, rng=rng)
    for _ in range(6):
        a = s.ask()
        assert np.all(np.abs(a) <= 1.0)
        s.tell_outcome(a, None, 2.0)  # every movement failed
    assert s.best_cost == 2.0


def test_probe_scale_sizes_probes_to_a_few_noise_units():
    scale = ProbeScale(noise=0.02, initial=0.5, low=0.01, high=5.0, target=3.0)
    assert scale.radius() == 0.5
    for _ in range(20):  # probes of 1 action unit that moved the outcome by 0.3
        scale.observe(1.0, 0.3)
    # the noise of the two casts (2 sigma^2) is removed from |dy|^2 before the sensitivity
    sensitivity = np.sqrt(0.3**2 - 2 * 0.02**2)
    assert scale.radius() == pytest.approx(3 * 0.02 / sensitivity, rel=1e-9)
    scale.observe(1.0, 0.0)  # a probe lost in the noise never makes the radius infinite
    assert scale.radius() <= 5.0


@pytest.mark.parametrize("kind", ["random", "nelder-mead"])
def test_other_optimisers_improve_their_best(kind):
    rng = np.random.default_rng(4)
    start = np.zeros(12)
    goal = J @ np.full(12, 0.2)
    c0 = float(np.linalg.norm(J @ start - goal))
    if kind == "random":
        s = RandomSearch(start, c0, sigma=0.1, rng=rng)
    else:
        mem = Memory(12, 2)
        for a in rng.uniform(-0.5, 0.5, (30, 12)):
            mem.add(a, J @ a)
        s = NelderMeadSearch(goal, mem, start, c0, step=0.1)
    _drive(s, goal, start, rng, 0.0, budget=30)
    assert s.best_cost < c0
