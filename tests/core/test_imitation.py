"""Imitation: |a - a_demo| < epsilon, actions in [-1, 1], the configured number of times."""

import numpy as np
import pytest

from sgim_nodes.core.environment import MovementResult, Status
from sgim_nodes.core.imitation import Imitation, perturb


@pytest.mark.parametrize("dim", [2, 24])
def test_perturbation_bound_and_box(dim):
    rng = np.random.default_rng(0)
    demo = rng.uniform(-1, 1, dim)
    demo[0], demo[1] = 1.0, -1.0  # on the box boundary: clipping must keep the bound
    eps = 0.2
    dev = []
    for _ in range(3000):
        a = perturb(demo, eps, rng)
        assert a.min() >= -1 and a.max() <= 1
        dev.append(np.linalg.norm(a - demo))
    dev = np.array(dev)
    assert dev.max() < eps
    assert dev.max() > 0.9 * eps  # the ball is actually used, not a degenerate point
    inner = np.clip(demo, -0.7, 0.7)  # far from the boundary, no clipping
    dirs = np.array([perturb(inner, eps, rng) - inner for _ in range(3000)])
    assert np.abs(dirs.mean(axis=0)).max() < 0.03  # centred on the demonstration


def test_imitation_runs_the_configured_number_of_times():
    rng = np.random.default_rng(1)
    demo_a, demo_y = np.zeros(3), np.array([0.5, 0.5])
    im = Imitation(demo_a, demo_y, count=4, epsilon=0.1, rng=rng)
    labels = []
    while not im.done:
        a, label = im.next_action()
        labels.append(label)
        im.observe(a, MovementResult(np.array([0.5, 0.4]), Status.OK))
    assert labels == ["imitation"] * 4
    assert im.best_distance == pytest.approx(0.1)
    with pytest.raises(RuntimeError):
        im.next_action()
    assert Imitation(demo_a, demo_y, count=0, epsilon=0.1, rng=rng).done
