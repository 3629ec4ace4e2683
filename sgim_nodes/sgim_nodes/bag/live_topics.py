"""A bag's topics on a live graph: the rclpy class of each recorded type and the QoS each
topic is published with. The recorder subscribes with them and replay publishes with them, so
a replayed bag reaches the same subscribers a live run does. Imports rclpy: the readers of
bags (bag/reader.py) never import this module.
"""

from __future__ import annotations

import importlib

from rclpy.qos import HistoryPolicy, QoSProfile

from sgim_nodes.bag.types import STATE_TOPICS
from sgim_ros import qos


def ros_message_class(msgtype: str) -> type:
    """The rclpy class of a rosbags type name such as 'sgim_msgs/msg/Movement'."""
    try:
        package, kind, name = msgtype.split("/")
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ValueError, ImportError, AttributeError) as error:
        raise ValueError(f"no ROS message class for type {msgtype!r}: {error}") from None


def topic_qos(topic: str, *, keep_all: bool = False) -> QoSProfile:
    """The graph's QoS for a topic (by its last name component)."""
    if topic.rsplit("/", 1)[-1] not in STATE_TOPICS:
        return qos.RECORDS
    if not keep_all:
        return qos.LATEST_STATE
    return QoSProfile(
        history=HistoryPolicy.KEEP_ALL,
        depth=1,
        reliability=qos.LATEST_STATE.reliability,
        durability=qos.LATEST_STATE.durability,
    )
