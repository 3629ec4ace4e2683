"""A re-executed movement replaces its first record in a live node's memory, as in the bag
readers' (bag/validation.py), whatever the two outcomes were."""

from __future__ import annotations

import numpy as np
import pytest

from sgim_nodes.core.memory import Memory

pytestmark = pytest.mark.ros


def _filled(n: int) -> Memory:
    memory = Memory(3, 2, min_tail=4, max_tail=8)
    rng = np.random.default_rng(0)
    for _ in range(n):
        memory.add(rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 2), "goal_directed")
    return memory


@pytest.mark.parametrize("n", [3, 40])  # a brute-force tail only, and a built KD-tree
def test_the_latest_pair_is_replaced_removed_or_added(n):
    from sgim_nodes.nodes.movement_memory import replace_latest

    memory = _filled(n)
    new = (np.full(3, 0.5), np.array([0.9, -0.9]), "exploration")
    row = replace_latest(memory, n - 1, new)
    assert row == n - 1 and len(memory) == n and memory.labels[-1] == "exploration"
    _, nearest = memory.nearest(np.array([0.9, -0.9]), 1)
    assert nearest[0] == n - 1  # the index sees the new outcome, not the old one
    assert replace_latest(memory, row, None) is None and len(memory) == n - 1  # failed now
    assert replace_latest(memory, None, new) == n - 1 and len(memory) == n  # ok now
    assert replace_latest(memory, None, None) is None and len(memory) == n
    with pytest.raises(ValueError, match="latest"):
        replace_latest(memory, 0, new)
