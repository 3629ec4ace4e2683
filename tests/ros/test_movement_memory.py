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


def test_a_live_memory_keeps_the_re_execution_and_refuses_rogue_records(rclpy_context):
    from sgim_msgs.msg import Movement
    from sgim_nodes.core.config import LearnerConfig
    from sgim_nodes.core.scale import unit_box
    from sgim_nodes.nodes.movement_memory import MovementMemory
    from sgim_ros import qos
    from tests.ros.graph_client import GraphClient

    client = GraphClient(rclpy_context, "memory_test")
    try:
        memory = MovementMemory(client.node, LearnerConfig(), 24, 2, unit_box(2, 0.07))
        pub = client.node.create_publisher(Movement, "/movements", qos.RECORDS)
        assert client.spin_until(lambda: pub.get_subscription_count() > 0)

        def movement(index, outcome, attempt=0, status=Movement.STATUS_OK):
            return Movement(index=index, process=Movement.PROCESS_RANDOM, status=status,
                            action=[0.1 * index] * 24, outcome=outcome, attempt=attempt)

        sent = [movement(1, [0.1, 0.1]), movement(2, [0.2, 0.2]),
                movement(3, [0.3, 0.3]),  # the dying simulator's record
                movement(3, [0.35, 0.35], attempt=1),  # its re-execution: replaces it
                movement(3, [0.9, 0.9], attempt=1),  # the same attempt again: a duplicate
                movement(2, [0.9, 0.9], attempt=5),  # not the latest movement
                movement(4, [float("nan"), 0.0]),  # non-finite
                movement(2_000_000, [0.5, 0.5]),  # far ahead
                movement(4, [], status=Movement.STATUS_NO_CONTACT),
                movement(4, [0.45, 0.45], attempt=1),  # a failed cast re-executed: landed
                movement(5, [0.5, 0.5])]
        for msg in sent:
            pub.publish(msg)
        assert client.spin_until(lambda: memory.count == 5)
        client.spin_for(0.3)
        assert memory.memory.outcomes.tolist() == [[0.1, 0.1], [0.2, 0.2], [0.35, 0.35],
                                                  [0.45, 0.45], [0.5, 0.5]]
        assert memory.gate.quarantined == 4
    finally:
        client.close()
