"""The fit cache answers exactly what a fresh local fit answers, as memory grows."""

import numpy as np
import pytest

from sgim_nodes.core import local_model
from sgim_nodes.core.fit_cache import FitCache
from sgim_nodes.core.memory import Memory


def _same(a, b):
    if a is None or b is None:
        return a is None and b is None
    return (np.array_equal(a.outcome, b.outcome) and np.array_equal(a.jacobian, b.jacobian)
            and a.n_effective == b.n_effective and a.held_out == b.held_out)


def test_every_answer_is_bit_identical_to_a_fresh_fit_while_memory_grows():
    rng = np.random.default_rng(0)
    mem = Memory(6, 2)
    cache = FitCache(mem, radius=0.6, max_pairs=20, capacity=64)
    for step in range(600):
        if len(mem) and rng.random() < 0.3:  # an action cast again: ties in action distance
            action = mem.actions[rng.integers(len(mem))].copy()
        else:
            action = rng.uniform(-1, 1, 6) * (0.3 if step % 2 else 1.0)
        mem.add(action, np.tanh(action[:2] + action[2:4]) + rng.normal(0, 0.02, 2))
        for i in rng.integers(len(mem), size=3):
            assert _same(cache.get(i), local_model.fit(mem, mem.actions[i], 0.6, 20))
    assert cache.hits > 0 and cache.misses > 0 and len(cache) <= 64


def test_a_pair_within_the_radius_makes_a_refit_and_one_beyond_it_does_not():
    mem = Memory(2, 2)
    for a in ([0.0, 0.0], [0.1, 0.0], [0.0, 0.1], [0.1, 0.1]):
        mem.add(np.array(a), np.array(a))
    cache = FitCache(mem, radius=0.5, max_pairs=60)
    first = cache.get(0)
    mem.add(np.array([0.9, 0.9]), np.zeros(2))  # beyond 0.5 of action 0
    assert cache.get(0) is first and cache.hits == 1
    mem.add(np.array([0.2, -0.1]), np.array([5.0, 5.0]))  # within: the fit must change
    refit = cache.get(0)
    assert refit is not first and cache.misses == 2
    assert _same(refit, local_model.fit(mem, mem.actions[0], 0.5, 60))


def test_capacity_must_be_positive():
    with pytest.raises(ValueError):
        FitCache(Memory(2, 2), 0.5, 60, capacity=0)
