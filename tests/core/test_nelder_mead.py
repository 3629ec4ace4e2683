"""Ask/tell Nelder-Mead: converges on a quadratic, counts only real evaluations, stays in
bounds."""

import numpy as np
import pytest

from sgim_nodes.core.nelder_mead import AskTellNelderMead


def _drive(nm, f, n):
    for _ in range(n):
        x = nm.ask()
        nm.tell(f(x))


def test_converges_on_a_quadratic():
    c = np.array([0.3, -0.2, 0.5])

    def f(x):
        return float(((x - c) ** 2).sum())

    rng = np.random.default_rng(0)
    nm = AskTellNelderMead(rng.uniform(-1, 1, (4, 3)))
    _drive(nm, f, 400)
    assert nm.best_f < 1e-8
    assert nm.best_x == pytest.approx(c, abs=1e-4)
    assert nm.n_evaluations == 400


def test_known_vertices_cost_no_evaluation():
    verts = np.array([[0.0, 0.0], [0.5, 0.0], [0.0, 0.5]])

    def f(x):
        return float(((x - 0.8) ** 2).sum())

    nm = AskTellNelderMead(verts, [f(v) for v in verts])
    assert nm.n_evaluations == 0
    # first asked point is already the reflection of the worst vertex (0, 0)
    assert nm.ask() == pytest.approx([0.5, 0.5])
    assert nm.ask() == pytest.approx([0.5, 0.5])  # asking twice does not advance
    _drive(nm, f, 100)
    assert nm.best_x == pytest.approx([0.8, 0.8], abs=1e-3)


def test_unknown_vertices_are_asked_first_and_bounds_hold():
    target = np.array([3.0, 3.0])  # outside the box: the optimum is the corner (1, 1)

    def f(x):
        return float(((x - target) ** 2).sum())

    verts = np.array([[0.9, 0.9], [0.5, 0.9], [0.9, 0.5]])
    nm = AskTellNelderMead(verts, [None, f(verts[1]), None])
    assert nm.ask() == pytest.approx([0.9, 0.9])
    nm.tell(f(verts[0]))
    assert nm.ask() == pytest.approx([0.9, 0.5])
    nm.tell(f(verts[2]))
    assert nm.n_evaluations == 2
    asked = []
    for _ in range(150):
        x = nm.ask()
        asked.append(x)
        nm.tell(f(x))
    asked = np.array(asked)
    assert asked.min() >= -1 and asked.max() <= 1
    assert nm.best_x == pytest.approx([1.0, 1.0], abs=1e-3)


def test_rejects_bad_simplex():
    with pytest.raises(ValueError):
        AskTellNelderMead(np.zeros((1, 3)))
    with pytest.raises(ValueError):
        AskTellNelderMead(np.zeros((3, 2)), [1.0])
