"""QoS profiles of the graph's topics.

Records (movements, goals, competences, demonstrations, evaluations) must never be dropped:
a RELIABLE KEEP_LAST queue of 100 lost most of a 2,000-message burst on these machines, while
KEEP_ALL delivered all of them. State topics (the region map) only matter at their latest
value, which late joiners should still get: TRANSIENT_LOCAL with depth 1.
"""

from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

RECORDS = QoSProfile(
    history=HistoryPolicy.KEEP_ALL,
    depth=1000,  # ignored under KEEP_ALL, kept for tools that display it
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)

LATEST_STATE = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
