"""Ask/tell Nelder-Mead.

Every evaluation of the cost is a REAL movement executed elsewhere (by a ROS service, or the
runner's loop), so the optimiser cannot call a function: it proposes a point (``ask``) and is
later told the measured cost (``tell``).  Vertices whose cost is already known (actions stored
in memory) are passed with their values and cost no movement.  Points are kept in the action
box [low, high] by clipping.
"""

from __future__ import annotations

from collections.abc import Generator, Sequence

import numpy as np

_Gen = Generator[np.ndarray, float, None]


class AskTellNelderMead:
    """Standard Nelder-Mead (reflection 1, expansion 2, contraction 0.5, shrink 0.5).

    The simplex may hold fewer than dim + 1 vertices: the search then stays in their affine
    hull (callers pad the simplex when they want the full space).
    """

    def __init__(self, vertices: np.ndarray, values: Sequence[float | None] | None = None,
                 low: float = -1.0, high: float = 1.0, reflection: float = 1.0,
                 expansion: float = 2.0, contraction: float = 0.5, shrink: float = 0.5) -> None:
        v = np.asarray(vertices, dtype=float)
        if v.ndim != 2 or len(v) < 2:
            raise ValueError("need at least 2 vertices of shape (n, dim)")
        self.low, self.high = low, high
        self.coef = (reflection, expansion, contraction, shrink)
        self._init_x = np.clip(v, low, high)
        self._init_f = list(values) if values is not None else [None] * len(v)
        if len(self._init_f) != len(v):
            raise ValueError("values must match vertices")
        self.n_evaluations = 0
        self.best_x: np.ndarray | None = None
        self.best_f = float("inf")
        self.simplex_x = self._init_x.copy()
        self.simplex_f = np.full(len(v), np.inf)
        self._gen: _Gen = self._run()
        self._pending: np.ndarray | None = next(self._gen)

    def _note(self, x: np.ndarray, f: float) -> None:
        if f < self.best_f:
            self.best_f, self.best_x = float(f), x.copy()

    def ask(self) -> np.ndarray:
        """The next point to evaluate (the same one until ``tell`` is called)."""
        assert self._pending is not None
        return self._pending.copy()

    def tell(self, value: float) -> None:
        """Report the measured cost of the last asked point."""
        assert self._pending is not None
        self.n_evaluations += 1
        self._note(self._pending, float(value))
        self._pending = self._gen.send(float(value))

    def spread(self) -> float:
        """Largest distance of a vertex to the best vertex (a convergence measure)."""
        return float(np.max(np.linalg.norm(self.simplex_x - self.simplex_x[0], axis=1)))

    def _clip(self, x: np.ndarray) -> np.ndarray:
        return np.clip(x, self.low, self.high)

    def _run(self) -> _Gen:
        xs, fs = self.simplex_x, self.simplex_f
        for i, f in enumerate(self._init_f):
            if f is None:
                f = yield xs[i].copy()
            fs[i] = f
            self._note(xs[i], float(f))
        r, e, c, s = self.coef
        while True:
            order = np.argsort(fs, kind="stable")
            xs[:], fs[:] = xs[order], fs[order]
            centroid = xs[:-1].mean(axis=0)
            xr = self._clip(centroid + r * (centroid - xs[-1]))
            fr = yield xr
            if fr < fs[0]:
                xe = self._clip(centroid + e * (xr - centroid))
                fe = yield xe
                xs[-1], fs[-1] = (xe, fe) if fe < fr else (xr, fr)
                continue
            if fr < fs[-2]:
                xs[-1], fs[-1] = xr, fr
                continue
            if fr < fs[-1]:  # outside contraction
                xc = self._clip(centroid + c * (xr - centroid))
                fc = yield xc
                if fc <= fr:
                    xs[-1], fs[-1] = xc, fc
                    continue
            else:  # inside contraction
                xc = self._clip(centroid + c * (xs[-1] - centroid))
                fc = yield xc
                if fc < fs[-1]:
                    xs[-1], fs[-1] = xc, fc
                    continue
            for i in range(1, len(xs)):  # shrink towards the best vertex
                xs[i] = self._clip(xs[0] + s * (xs[i] - xs[0]))
                fs[i] = yield xs[i].copy()
