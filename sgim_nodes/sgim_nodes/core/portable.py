"""The learner's small linear algebra and elementary functions, rounded alike on every CPU.

Why: goal babbling amplifies a difference in the last bit into another run, and numpy's fast
paths round differently on different x86-64 CPUs. Its BLAS and LAPACK (``@``, ``np.dot``,
``np.linalg.norm`` of a whole vector, ``solve``, ``qr``, ``lstsq``) pick their kernels by CPU
model, and ``np.exp``, ``np.cos``, ``np.sin`` and ``np.power`` have AVX-512 versions
(``DOUBLE_exp_X86_V4`` and the like) that differ from the others. The same seed then gave
another run on an Intel Xeon than on an AMD EPYC, and on one machine under another
``OPENBLAS_CORETYPE``.

Here every result is made of operations whose rounding IEEE 754 fixes (elementwise ``+``,
``-``, ``*``, ``/``, ``sqrt``) and of numpy's sums, whose order depends on the array's shape,
never on the CPU; the elementary functions come from the C library one value at a time
(glibc's, the same on every machine of one image). The sizes are small (a 25 x 25 system
per local fit, 2 x 2 elsewhere), so this costs little: benchmarks/bench_inverse_speed.py prints
the run time. tests/core/test_portable.py checks the results against numpy's and that a run
is the same under every BLAS kernel and numpy SIMD level this machine can select.
"""

from __future__ import annotations

import math

import numpy as np

_exp = np.frompyfunc(math.exp, 1, 1)
_cos = np.frompyfunc(math.cos, 1, 1)
_sin = np.frompyfunc(math.sin, 1, 1)


def exp(x: np.ndarray | float) -> np.ndarray:
    """e**x elementwise, from the C library."""
    return np.asarray(_exp(np.asarray(x, dtype=float)), dtype=float)


def cos(x: np.ndarray | float) -> np.ndarray:
    """cos(x) elementwise, from the C library."""
    return np.asarray(_cos(np.asarray(x, dtype=float)), dtype=float)


def sin(x: np.ndarray | float) -> np.ndarray:
    """sin(x) elementwise, from the C library."""
    return np.asarray(_sin(np.asarray(x, dtype=float)), dtype=float)


def matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` for 1-D and 2-D operands, as products summed along the shared axis."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.ndim == 1 and b.ndim == 1:
        return (a * b).sum()
    if a.ndim == 2 and b.ndim == 1:
        return (a * b[None, :]).sum(axis=1)
    if a.ndim == 1 and b.ndim == 2:
        return (a[:, None] * b).sum(axis=0)
    if a.ndim == 2 and b.ndim == 2:
        return (a[:, :, None] * b[None, :, :]).sum(axis=1)
    raise ValueError(f"matmul takes 1-D and 2-D operands, got {a.ndim}-D and {b.ndim}-D")


def norm(v: np.ndarray) -> float:
    """The Euclidean norm of all of ``v``'s entries."""
    v = np.asarray(v, dtype=float).ravel()
    return float(np.sqrt((v * v).sum()))


def cholesky(a: np.ndarray) -> np.ndarray:
    """Lower-triangular L with L L^T = a, for a symmetric positive definite ``a``
    (ValueError if it is not)."""
    a = np.asarray(a, dtype=float)
    n = len(a)
    lower = np.zeros_like(a)
    for j in range(n):
        row = lower[j, :j]
        pivot = a[j, j] - (row * row).sum()
        if not pivot > 0.0:
            raise ValueError("the matrix is not positive definite")
        lower[j, j] = math.sqrt(pivot)
        if j + 1 < n:
            lower[j + 1:, j] = (a[j + 1:, j] - (lower[j + 1:, :j] * row).sum(axis=1)
                                ) / lower[j, j]
    return lower


def solve_spd(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """x with a x = b, for a symmetric positive definite ``a`` (b a vector or columns)."""
    lower = cholesky(a)
    b = np.asarray(b, dtype=float)
    vector = b.ndim == 1
    y = np.array(b[:, None] if vector else b, dtype=float)
    n = len(lower)
    for i in range(n):  # L y = b
        y[i] = (y[i] - (lower[i, :i, None] * y[:i]).sum(axis=0)) / lower[i, i]
    for i in range(n - 1, -1, -1):  # L^T x = y
        y[i] = (y[i] - (lower[i + 1:, i, None] * y[i + 1:]).sum(axis=0)) / lower[i, i]
    return y[:, 0] if vector else y


def minimum_norm_step(jac: np.ndarray, gap: np.ndarray) -> np.ndarray:
    """The smallest delta with jac delta = gap (jac: outcomes x actions, full row rank), with a
    relative damping of 1e-9 that keeps it defined when the rows are nearly dependent."""
    gram = matmul(jac, jac.T)
    mu = 1e-9 * max(float(np.trace(gram)), 1e-12)
    return matmul(jac.T, solve_spd(gram + mu * np.eye(len(gram)), gap))


def least_squares(design: np.ndarray, y: np.ndarray) -> np.ndarray:
    """beta minimising |design beta - y|, by the normal equations with a damping of 1e-12
    of their trace (defined, and close to the minimum-norm answer, when the columns are
    dependent)."""
    design = np.asarray(design, dtype=float)
    gram = matmul(design.T, design)
    gram += 1e-12 * max(float(np.trace(gram)), 1e-300) * np.eye(len(gram))
    return solve_spd(gram, matmul(design.T, np.asarray(y, dtype=float)))


def orthonormal_columns(m: np.ndarray) -> np.ndarray:
    """Orthonormal columns spanning those of ``m`` (n x k, rank k), by modified
    Gram-Schmidt: the first column's direction is kept, each next one made orthogonal."""
    q = np.array(m, dtype=float)
    for j in range(q.shape[1]):
        for i in range(j):
            q[:, j] -= (q[:, i] * q[:, j]).sum() * q[:, i]
        q[:, j] /= norm(q[:, j])
    return q
