"""Memory of (action, outcome) pairs with fast nearest-neighbour queries on outcomes.

The inverse model asks dozens of neighbour queries per movement, so queries must stay well
under 1 ms at 10,000 pairs while pairs arrive one by one.  A scipy cKDTree indexes the bulk and
a small recent tail is searched by brute force; the tree is rebuilt when the tail outgrows a
fraction of the indexed part (geometric rebuilds while the memory is small) or ``max_tail``
rows (so the brute-force part, hence the query time, stays bounded).  A rebuild of 10,000 2-D
points takes ~1-2 ms, so even one rebuild per 512 inserts costs little over a 5000-movement run.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from scipy.spatial import cKDTree


class Memory:
    """Growing arrays of actions, outcomes and process labels.

    Only successful movements are stored: a failed movement has no outcome to learn from.
    """

    def __init__(self, action_dim: int, outcome_dim: int, rebuild_fraction: float = 0.5,
                 min_tail: int = 64, max_tail: int = 512, capacity: int = 1024) -> None:
        self.action_dim = action_dim
        self.outcome_dim = outcome_dim
        self.rebuild_fraction = rebuild_fraction
        self.min_tail = min_tail
        self.max_tail = max(max_tail, min_tail)
        self._actions = np.empty((capacity, action_dim))
        self._outcomes = np.empty((capacity, outcome_dim))
        self.labels: list[str] = []
        self._n = 0
        self._tree: cKDTree | None = None
        self._n_indexed = 0
        self.n_rebuilds = 0

    def __len__(self) -> int:
        return self._n

    @property
    def actions(self) -> np.ndarray:
        return self._actions[: self._n]

    @property
    def outcomes(self) -> np.ndarray:
        return self._outcomes[: self._n]

    def add(self, action: np.ndarray, outcome: np.ndarray, label: str = "") -> int:
        """Store one pair; returns its index."""
        if self._n == len(self._actions):
            cap = 2 * len(self._actions)
            self._actions = np.resize(self._actions, (cap, self.action_dim))
            self._outcomes = np.resize(self._outcomes, (cap, self.outcome_dim))
        self._actions[self._n] = action
        self._outcomes[self._n] = outcome
        self.labels.append(label)
        self._n += 1
        tail = self._n - self._n_indexed
        if tail > max(self.min_tail, min(self.max_tail, self.rebuild_fraction * self._n_indexed)):
            self._rebuild()
        return self._n - 1

    def _rebuild(self) -> None:
        # Imported here: scipy.spatial takes about 0.4 s of CPU to import, which every node of
        # the graph that imports the core (most never build a memory) paid at each start.
        from scipy.spatial import cKDTree

        self._tree = cKDTree(self._outcomes[: self._n].copy())
        self._n_indexed = self._n
        self.n_rebuilds += 1

    def nearest(self, query: np.ndarray, k: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """The min(k, len) stored outcomes nearest to each query point.

        query (m,) -> (distances (k,), indices (k,)); query (q, m) -> arrays (q, k).
        Sorted by distance; ties broken by index so results are deterministic.
        """
        q = np.asarray(query, dtype=float)
        single = q.ndim == 1
        q2 = q[None, :] if single else q
        k = min(k, self._n)
        if k <= 0:
            empty = np.empty((len(q2), 0))
            return (empty[0], empty[0].astype(int)) if single else (empty, empty.astype(int))
        parts_d, parts_i = [], []
        if self._tree is not None and self._n_indexed > 0:
            kt = min(k, self._n_indexed)
            d, i = self._tree.query(q2, k=kt)
            parts_d.append(np.asarray(d).reshape(len(q2), kt))
            parts_i.append(np.asarray(i).reshape(len(q2), kt))
        if self._n > self._n_indexed:
            tail = self._outcomes[self._n_indexed: self._n]
            d = np.sqrt(((q2[:, None, :] - tail[None, :, :]) ** 2).sum(-1))
            kt = min(k, len(tail))
            idx = np.argsort(d, axis=1, kind="stable")[:, :kt]
            parts_d.append(np.take_along_axis(d, idx, axis=1))
            parts_i.append(idx + self._n_indexed)
        dist = np.concatenate(parts_d, axis=1)
        ind = np.concatenate(parts_i, axis=1)
        order = np.lexsort((ind, dist), axis=1)[:, :k] if dist.shape[1] > k else \
            np.lexsort((ind, dist), axis=1)
        dist = np.take_along_axis(dist, order, axis=1)
        ind = np.take_along_axis(ind, order, axis=1)
        return (dist[0], ind[0]) if single else (dist, ind)

    def nearest_actions(self, action: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The min(k, len) stored actions nearest to ``action`` (Euclidean, in action space):
        (distances (k,), indices (k,)), sorted, ties by index.  Brute force: at 5000 pairs of
        24 numbers one query is ~0.1 ms, and the action space has too many dimensions for a
        KD-tree to prune."""
        k = min(k, self._n)
        if k <= 0:
            return np.empty(0), np.empty(0, dtype=int)
        diff = self._actions[: self._n] - np.asarray(action, dtype=float)
        d2 = np.einsum("ij,ij->i", diff, diff)
        if k < self._n:
            # Every pair as close as the k-th, so that ties there go by index too: a repeated
            # action is common (an inverse answer cast again), and argpartition alone picks
            # among equal distances by the array's length, not by index.
            kth = d2[np.argpartition(d2, k - 1)[k - 1]]
            idx = np.flatnonzero(d2 <= kth)
        else:
            idx = np.arange(self._n)
        idx = idx[np.lexsort((idx, d2[idx]))[:k]]
        return np.sqrt(d2[idx]), idx

    def closest_distance(self, point: np.ndarray) -> float:
        """Distance from a point to the closest stored outcome (inf when empty)."""
        if self._n == 0:
            return float("inf")
        d, _ = self.nearest(point, 1)
        return float(d[0])
