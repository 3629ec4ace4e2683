"""Memory nearest neighbours equal brute force across index rebuilds, and are fast."""

import numpy as np

from sgim_nodes.core.memory import Memory


def _brute(outcomes, q, k):
    d = np.linalg.norm(outcomes - q, axis=1)
    return np.sort(d)[:k]


def test_nearest_matches_brute_force_while_growing():
    rng = np.random.default_rng(0)
    mem = Memory(3, 2, rebuild_fraction=0.5, min_tail=16)
    assert len(mem) == 0 and mem.closest_distance(np.zeros(2)) == float("inf")
    checked = 0
    for n in range(1, 1500):
        mem.add(rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 2), "random")
        if n in (1, 2, 5, 17, 40, 100, 333, 777, 1499):
            for q in rng.uniform(-1.2, 1.2, (5, 2)):
                for k in (1, 3, 10):
                    d, i = mem.nearest(q, k)
                    assert len(d) == min(k, n)
                    assert np.allclose(d, _brute(mem.outcomes, q, k))
                    assert np.allclose(np.linalg.norm(mem.outcomes[i] - q, axis=1), d)
                    checked += 1
    assert checked == 9 * 5 * 3
    assert 1 < mem.n_rebuilds < 30  # geometric rebuilds, not one per insert
    # batched queries agree with single ones
    qs = rng.uniform(-1, 1, (4, 2))
    d_b, i_b = mem.nearest(qs, 5)
    for j, q in enumerate(qs):
        d_s, i_s = mem.nearest(q, 5)
        assert np.array_equal(i_b[j], i_s) and np.allclose(d_b[j], d_s)


def test_actions_and_labels_are_kept_in_order():
    mem = Memory(2, 2, capacity=2)  # forces the arrays to grow
    for j in range(5):
        mem.add(np.array([j, -j]), np.array([0.1 * j, 0.0]), f"l{j}")
    assert mem.actions[:, 0].tolist() == [0, 1, 2, 3, 4]
    assert mem.labels == ["l0", "l1", "l2", "l3", "l4"]
    _, i = mem.nearest(np.array([0.29, 0.0]), 2)
    assert i.tolist() == [3, 2]


def test_the_brute_force_tail_stays_bounded_as_memory_grows_to_10000():
    """What keeps a query fast at any size (benchmarks/bench_memory.py prints the times): the
    unindexed tail searched by brute force never exceeds max_tail, with rebuilds geometric
    while memory is small."""
    rng = np.random.default_rng(1)
    mem = Memory(24, 2, max_tail=512)
    largest_tail = 0
    for _ in range(10000):
        mem.add(rng.uniform(-1, 1, 24), rng.uniform(-1, 1, 2))
        largest_tail = max(largest_tail, len(mem) - mem._n_indexed)
    assert largest_tail <= 512
    assert mem.n_rebuilds < 40  # not one per insert: 10000 / 512 plus the geometric start
    q = rng.uniform(-1, 1, 2)
    d, _ = mem.nearest(q, 10)
    assert np.allclose(d, _brute(mem.outcomes, q, 10))


def test_nearest_actions_break_ties_at_the_kth_by_index_whatever_the_memory_size():
    """Repeated actions are common (an inverse answer cast again): which of several equally
    near pairs is kept must not depend on how many pairs memory holds."""
    rng = np.random.default_rng(4)
    mem = Memory(3, 2)
    repeated = np.full(3, 0.5)
    for i in range(40):
        mem.add(repeated if i % 4 == 0 else rng.uniform(-1, 1, 3), np.zeros(2))
    tied = np.flatnonzero(np.all(mem.actions == repeated, axis=1))  # 10 copies
    centre = repeated + np.array([0.1, 0.0, 0.0])
    for extra in range(600):
        _, idx = mem.nearest_actions(centre, 4)
        assert list(idx) == list(tied[:4]), f"after {extra} far pairs"
        mem.add(rng.uniform(2, 3, 3), np.zeros(2))  # far away: the answer must not change
