"""core/portable.py: the learner's linear algebra gives numpy's answers to rounding, and its
results do not depend on the BLAS kernel or numpy's SIMD level (those are what made runs
differ between CPU models)."""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from sgim_nodes.core import portable
from tests.conftest import REPO


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(0)


def test_products_and_norms_match_numpy(rng):
    a, b = rng.standard_normal((7, 5)), rng.standard_normal((5, 3))
    v, w = rng.standard_normal(5), rng.standard_normal(7)
    np.testing.assert_allclose(portable.matmul(a, b), a @ b, rtol=1e-13)
    np.testing.assert_allclose(portable.matmul(a, v), a @ v, rtol=1e-13)
    np.testing.assert_allclose(portable.matmul(w, a), w @ a, rtol=1e-13)
    assert portable.matmul(v, v) == pytest.approx(v @ v, rel=1e-14)
    assert portable.norm(a) == pytest.approx(np.linalg.norm(a), rel=1e-14)
    with pytest.raises(ValueError, match="1-D and 2-D"):
        portable.matmul(np.ones((2, 2, 2)), v)


def test_elementary_functions_are_the_c_librarys(rng):
    x = rng.uniform(-20, 20, 50)
    assert [float(v) for v in portable.exp(x)] == [math.exp(v) for v in x]
    assert [float(v) for v in portable.cos(x)] == [math.cos(v) for v in x]
    assert [float(v) for v in portable.sin(x)] == [math.sin(v) for v in x]
    assert portable.exp(np.zeros((2, 3))).shape == (2, 3)


def test_symmetric_solves_and_least_squares(rng):
    m = rng.standard_normal((30, 25))
    gram = m.T @ m + 0.1 * np.eye(25)
    lower = portable.cholesky(gram)
    np.testing.assert_allclose(lower @ lower.T, gram, rtol=1e-12, atol=1e-12)
    assert np.allclose(np.triu(lower, 1), 0.0)
    rhs = rng.standard_normal((25, 4))
    np.testing.assert_allclose(portable.solve_spd(gram, rhs), np.linalg.solve(gram, rhs),
                               rtol=1e-9)
    np.testing.assert_allclose(portable.solve_spd(gram, rhs[:, 0]),
                               np.linalg.solve(gram, rhs[:, 0]), rtol=1e-9)
    with pytest.raises(ValueError, match="positive definite"):
        portable.cholesky(-np.eye(3))
    design, y = rng.standard_normal((12, 3)), rng.standard_normal((12, 2))
    np.testing.assert_allclose(portable.least_squares(design, y),
                               np.linalg.lstsq(design, y, rcond=None)[0], rtol=1e-8)


def test_minimum_norm_step_reaches_the_gap_with_the_smallest_step(rng):
    jac, gap = rng.standard_normal((2, 24)), rng.standard_normal(2)
    step = portable.minimum_norm_step(jac, gap)
    np.testing.assert_allclose(jac @ step, gap, rtol=1e-7)
    np.testing.assert_allclose(step, np.linalg.pinv(jac) @ gap, rtol=1e-7)


def test_orthonormal_columns_span_the_input(rng):
    m = rng.standard_normal((24, 3))
    q = portable.orthonormal_columns(m)
    np.testing.assert_allclose(q.T @ q, np.eye(3), atol=1e-13)
    # same span: projecting m on q's columns gives m back; the first direction is kept
    np.testing.assert_allclose(q @ (q.T @ m), m, atol=1e-12)
    np.testing.assert_allclose(q[:, 0], m[:, 0] / np.linalg.norm(m[:, 0]), rtol=1e-13)


def test_the_learners_own_code_uses_no_cpu_dependent_numpy():
    """The BLAS/LAPACK calls and the ufuncs numpy has AVX-512 versions of stay out of the
    learner's core and world (a new one would make runs differ between CPU models)."""
    import ast

    linalg = {"solve", "lstsq", "qr", "inv", "pinv", "svd", "eig", "eigh", "det", "cholesky"}
    ufuncs = {"dot", "matmul", "inner", "vdot", "tensordot", "exp", "cos", "sin", "tan",
              "power", "log", "arctan2", "hypot"}

    def name(node: ast.AST) -> str:
        return f"{name(node.value)}.{node.attr}" if isinstance(node, ast.Attribute) else (
            node.id if isinstance(node, ast.Name) else "?")

    files = [*(REPO / "sgim_nodes" / "sgim_nodes" / "core").glob("*.py"),
             *(REPO / "sim_bridge" / "sim_bridge" / f for f in (
                 "fishing_world.py", "bezier.py", "scaling.py", "data_files.py"))]
    found = []
    for file in files:
        if file.name == "portable.py":
            continue
        for node in ast.walk(ast.parse(file.read_text())):
            where = f"{file.name}:{getattr(node, 'lineno', '?')}"
            if isinstance(node, ast.BinOp) and isinstance(node.op, ast.MatMult):
                found.append(f"{where}: @")
            if not isinstance(node, ast.Call):
                continue
            called = name(node.func)
            if (called in {f"np.linalg.{f}" for f in linalg}
                    or called in {f"np.{f}" for f in ufuncs}
                    or (called == "np.linalg.norm"
                        and not any(k.arg == "axis" for k in node.keywords))
                    or called.endswith(".dot")):
                found.append(f"{where}: {called}")
    assert not found, "\n".join(found)


@pytest.mark.slow
def test_runs_are_the_same_under_other_blas_kernels_and_simd_levels():
    """The reference runs (tests/golden_runs.py) under the oldest BLAS kernel OpenBLAS has and
    numpy's baseline SIMD only: what another CPU model would pick. The digests are those the
    graph test checks with this machine's own choices. Without the evaluations: they cast in a
    world of their own and leave the learner as it was (the graph's evaluator is another
    process, and its movements are the runner's), so the movements, all a digest holds, are
    the same, for a third of the casts."""
    code = ("import sys, json; from tests.golden_runs import DIGESTS, runner_digest, "
            "runner_records; print(json.dumps({l: runner_digest(runner_records(l, "
            "eval_every=0)) for l in DIGESTS}))")
    env = dict(os.environ, OPENBLAS_CORETYPE="Prescott",
               NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4 AVX512_ICL AVX512_SPR",
               PYTHONPATH=os.pathsep.join(str(REPO / p) for p in ("", "sgim_nodes",
                                                                  "sim_bridge")))
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=REPO, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    import json

    from tests.golden_runs import DIGESTS

    assert json.loads(out.stdout.strip().splitlines()[-1]) == DIGESTS
