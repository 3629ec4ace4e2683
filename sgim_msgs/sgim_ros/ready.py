"""The "ready" check of a node that must hear a run from its first record.

DDS matches a publisher and a subscription some time after both exist, and a message
published before the match is lost to that subscriber without a trace. Under load the match
can take seconds. So the arbiter, before its first movement, asks every node that listens to
the run's records (the recorder, the evaluator, the teacher, the explorer, the imitation
node) whether it has matched at least the publishers that the arbiter itself sees on each
topic (sgim_msgs/srv/RecorderReady); it starts only when every one says yes.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rclpy.node import Node

from sgim_msgs.srv import RecorderReady


def unmatched(subscriptions: Mapping[str, Any], topics: list[str],
              publishers: list[int]) -> list[str]:
    """The topics (as 'name (have/wanted)') whose subscription has matched fewer publishers
    than `publishers` says; a topic this node does not listen to is not its concern."""
    missing = []
    for topic, wanted in zip(topics, publishers, strict=False):
        sub = subscriptions.get(topic)
        if sub is None:
            continue
        have = sub.get_publisher_count()
        if have < wanted:
            missing.append(f"{topic} ({have}/{wanted})")
    return missing


def serve_ready(node: Node, service: Any, subscriptions: Mapping[str, Any],
                servers: Mapping[str, Any] | None = None) -> Any:
    """Serve `service` (a RecorderReady endpoint, made by its `create(node, callback)`: the
    node's declaration) for `subscriptions`, keyed by the topic name as
    subscribed (relative, e.g. 'movements' or 'markers/landings'): ready when
    each one the caller names has matched at least as many publishers as the caller sees,
    and when this node's clients in `servers` (by service name) see their server (a node that
    calls a service in the middle of a job must not find it missing on its first call).
    The mapping is read at each call, so subscriptions added later count too."""
    if not subscriptions:
        raise ValueError(f"{service.name}: a ready service needs at least one subscription")

    def answer(request: RecorderReady.Request, response: RecorderReady.Response):
        missing = unmatched(subscriptions, list(request.topics), list(request.publishers))
        missing += [f"no {name} server" for name, client in (servers or {}).items()
                    if not client.service_is_ready()]
        response.ready = not missing
        response.message = "" if not missing else "not yet matched: " + ", ".join(missing)
        return response

    return service.create(node, answer)
