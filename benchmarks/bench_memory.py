"""Memory benchmark: nearest-neighbour query time at 10,000 pairs and the total index upkeep
over a 5000-insert run (the issue's budget: <= 1 ms per query, small upkeep).

Run: .venv/bin/python benchmarks/bench_memory.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "sgim_nodes"))

from sgim_nodes.core.memory import Memory

ACTION_DIM = 24  # the fishing world's action dimension


def fill(mem: Memory, n: int, rng: np.random.Generator) -> tuple[float, float]:
    """Insert n pairs; returns (total insert+upkeep time, time spent in index rebuilds)."""
    rebuild_time = 0.0
    original = mem._rebuild

    def timed_rebuild() -> None:
        nonlocal rebuild_time
        t = time.perf_counter()
        original()
        rebuild_time += time.perf_counter() - t

    mem._rebuild = timed_rebuild  # type: ignore[method-assign]
    acts = rng.uniform(-1, 1, (n, mem.action_dim))
    outs = rng.uniform(-1, 1, (n, mem.outcome_dim))
    t = time.perf_counter()
    for a, y in zip(acts, outs, strict=True):
        mem.add(a, y)
    total = time.perf_counter() - t
    mem._rebuild = original  # type: ignore[method-assign]
    return total, rebuild_time


def query_times(mem: Memory, rng: np.random.Generator, k: int, n: int = 2000) -> np.ndarray:
    times = np.empty(n)
    for i, q in enumerate(rng.uniform(-1, 1, (n, mem.outcome_dim))):
        t = time.perf_counter()
        mem.nearest(q, k)
        times[i] = time.perf_counter() - t
    return times


def main() -> None:
    rng = np.random.default_rng(0)
    mem = Memory(ACTION_DIM, 2)
    total, rebuild = fill(mem, 5000, rng)
    print(f"5000 inserts: total {total * 1e3:.1f} ms, of which index upkeep (KD-tree rebuilds) "
          f"{rebuild * 1e3:.1f} ms in {mem.n_rebuilds} rebuilds "
          f"({total / 5000 * 1e6:.1f} us per insert)")
    fill(mem, 5000, rng)
    print(f"memory size {len(mem)}, indexed {mem._n_indexed}, brute-force tail "
          f"{len(mem) - mem._n_indexed}")
    for k in (1, 10):
        t = query_times(mem, rng, k) * 1e6
        print(f"NN query at 10,000 pairs, k={k:2d}: median {np.median(t):.1f} us, "
              f"p99 {np.percentile(t, 99):.1f} us, max {t.max():.1f} us")
    # worst case: the query time at the largest brute-force tail met while inserting
    worst_tail, worst_t = 0, []
    for _ in range(3000):
        mem.add(rng.uniform(-1, 1, ACTION_DIM), rng.uniform(-1, 1, 2))
        tail = len(mem) - mem._n_indexed
        if tail >= worst_tail:
            q = rng.uniform(-1, 1, 2)
            t = time.perf_counter()
            mem.nearest(q, 10)
            dt = time.perf_counter() - t
            worst_t = [dt] if tail > worst_tail else [*worst_t, dt]
            worst_tail = tail
    print(f"NN query at the largest tail met ({worst_tail} rows, {len(mem)} pairs), k=10: "
          f"median {np.median(worst_t) * 1e6:.1f} us over {len(worst_t)} queries")

if __name__ == "__main__":
    main()
