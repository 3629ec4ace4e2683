"""Local fits centred on stored actions, kept until memory changes within their radius.

Why: the local-linear inverse model fits one linear model around each of its l_max candidate
actions for every goal (local_model.fit), and those fits were three quarters of a learner's
CPU time on the 20-joint arm (cProfile; benchmarks/bench_inverse_speed.py prints the run time
with and without the cache). A fit centred on a stored action depends only on the pairs
within ``radius`` of that action in action space (at most ``max_pairs`` of them, the
nearest, ties by index): memory only grows, so the fit stays exactly what it was until a new
pair lands within that radius. The cache keeps each fit until then, so every answer is
bit-identical to a fresh fit (a test compares them), and the graph's nodes, each with its own
memory and cache, still make the single-process runner's movements.
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from . import local_model
from .memory import Memory

DEFAULT_CAPACITY = 1024
"""Fits kept at most (least recently used dropped first): about 13 kB each with the data their
held-out error needs, so ~13 MB per model; a 5000-movement run asks for a few thousand."""

_MARGIN = 1.0 + 1e-9
"""A new pair this close to the radius also invalidates: dropping a fit that was still valid
only costs a refit, keeping a stale one would change an answer."""

_BLOCK = 64
"""New pairs compared with the cached centres at a time (a resumed run adds thousands)."""


class FitCache:
    """``get(index)`` is ``local_model.fit(memory, memory.actions[index], radius, max_pairs)``,
    computed once per state of the pairs around that action."""

    def __init__(self, memory: Memory, radius: float, max_pairs: int,
                 capacity: int = DEFAULT_CAPACITY) -> None:
        if capacity < 1:
            raise ValueError(f"capacity must be >= 1, got {capacity}")
        self.memory = memory
        self.radius = float(radius)
        self.max_pairs = int(max_pairs)
        self.capacity = int(capacity)
        self._fits: OrderedDict[int, local_model.LocalFit | None] = OrderedDict()
        self._seen = len(memory)
        self.hits = 0
        self.misses = 0

    def get(self, index: int) -> local_model.LocalFit | None:
        self._forget_stale()
        index = int(index)
        if index in self._fits:
            self.hits += 1
            self._fits.move_to_end(index)
            return self._fits[index]
        self.misses += 1
        mem = self.memory
        fitted = local_model.fit(mem, mem.actions[index], self.radius, self.max_pairs)
        self._fits[index] = fitted
        if len(self._fits) > self.capacity:
            self._fits.popitem(last=False)
        return fitted

    def __len__(self) -> int:
        return len(self._fits)

    def _forget_stale(self) -> None:
        """Drop the fits with a pair stored since the last call within their radius."""
        n = len(self.memory)
        if n == self._seen:
            return
        if n < self._seen:  # not a memory that only grows: trust nothing
            self._fits.clear()
        elif self._fits:
            keys = np.fromiter(self._fits, dtype=int, count=len(self._fits))
            actions = self.memory.actions
            centres = actions[keys]
            stale = np.zeros(len(keys), dtype=bool)
            for start in range(self._seen, n, _BLOCK):  # bounded temporaries on a bulk load
                new = actions[start:min(n, start + _BLOCK)]
                diff = new[:, None, :] - centres[None, :, :]
                d2 = np.einsum("nkd,nkd->nk", diff, diff)
                stale |= np.any(d2 <= (self.radius * _MARGIN) ** 2, axis=0)
            for key in keys[stale]:
                del self._fits[int(key)]
        self._seen = n
