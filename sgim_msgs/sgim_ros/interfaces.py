"""What a node publishes, subscribes to, serves and calls: declared once, created from it.

Each node module lists its endpoints in a module-level INTERFACES, beside its PARAMS, and
creates each one from its declaration (`endpoint.create(node, callback)`), so the code cannot
make an endpoint its declaration does not name. A helper that creates endpoints for its node
(SimClient, MovementMemory, PaceControl...) declares them as a constant that the node's
INTERFACES includes. The graph description, the arbiter's start, the recorder and
docs/reference.md read the declarations; tests/docs/test_reference.py builds every node and
checks that it made exactly what it declares. A publisher of a record that teaches the learner
signs each record it sends (SigningPublisher).

The tables below type every topic, service and action of the graph once, so a node declares
only a name and the condition under which it has it. Nothing here imports rclpy until an
endpoint is made: the bag readers use the topic table without ROS.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

PACKAGE = "sgim_msgs"
# The learner's records: every topic a run records and load_run reads, as rosbags type names.
# STATE_TOPICS keep only their latest value (LATEST_STATE QoS); the others are records
# (RECORDS QoS).
TOPICS: dict[str, str] = {
    "movements": f"{PACKAGE}/msg/Movement",
    "goals": f"{PACKAGE}/msg/Goal",
    "competences": f"{PACKAGE}/msg/Competence",
    "region_map": f"{PACKAGE}/msg/RegionMap",
    "demonstrations": f"{PACKAGE}/msg/Demonstration",
    "demonstrations_taken": f"{PACKAGE}/msg/Demonstration",
    "help_requests": f"{PACKAGE}/msg/HelpRequest",
    "teacher_checks": f"{PACKAGE}/msg/TeacherCheck",
    "evaluations": f"{PACKAGE}/msg/Evaluation",
    "run_status": f"{PACKAGE}/msg/RunStatus",
}
# What a run also records for viewers (Foxglove, rviz2): the arbiter's pace and the markers
# node's live picture (docs/markers.md). They are not learner records: load_run ignores them.
VIEW_TOPICS: dict[str, str] = {
    "pace_state": f"{PACKAGE}/msg/PaceState",
    "markers/landings": "visualization_msgs/msg/MarkerArray",
    "markers/regions": "visualization_msgs/msg/MarkerArray",
    "markers/teaching_goals": "visualization_msgs/msg/MarkerArray",
    "markers/current_goal": "visualization_msgs/msg/MarkerArray",
}
RECORDED_TOPICS: dict[str, str] = {**TOPICS, **VIEW_TOPICS}
# By last name component (names may be namespaced): the topics that hold a state, not records.
STATE_TOPICS = frozenset({"region_map", "pace_state", "regions", "teaching_goals",
                          "current_goal"})
KINDS = ("publishes", "subscribes", "serves", "calls", "action server", "action client")
CLIENT_KINDS = ("calls", "action client")
TOPIC_KINDS = ("publishes", "subscribes")
READY_TYPE = f"{PACKAGE}/srv/RecorderReady"  # every `*_ready` service (sgim_ros/ready.py)
SERVICES = {
    "execute_action": f"{PACKAGE}/srv/ExecuteAction",
    "choose_goal": f"{PACKAGE}/srv/ChooseGoal",
    "register_demonstration": f"{PACKAGE}/srv/RegisterDemonstration",
    "pace": f"{PACKAGE}/srv/Pace",
}
ACTIONS = {"reach_goal": f"{PACKAGE}/action/ReachGoal", "imitate": f"{PACKAGE}/action/Imitate"}


class UnknownEndpoint(ValueError):
    """A declaration names a topic, service or action that no table types."""


def _last(name: str) -> str:
    return name.rsplit("/", 1)[-1]


def ros_message_class(msgtype: str) -> type:
    """The rclpy class of a type name such as 'sgim_msgs/msg/Movement' (or a service's, an
    action's)."""
    try:
        package, kind, name = msgtype.split("/")
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ValueError, ImportError, AttributeError) as error:
        raise ValueError(f"no ROS message class for type {msgtype!r}: {error}") from None


def qos_role(topic: str, *, keep_all: bool = False) -> str:
    """A topic's QoS role (by its last name component, sgim_ros/qos.py): RECORDS, or
    LATEST_STATE for a state topic, kept whole with `keep_all` (the recorder's)."""
    if _last(topic) not in STATE_TOPICS:
        return "RECORDS"
    return "LATEST_STATE, keep-all" if keep_all else "LATEST_STATE"


def topic_qos(topic: str, *, keep_all: bool = False) -> Any:
    """The graph's QoS profile for a topic: its role's (qos_role)."""
    from rclpy.qos import HistoryPolicy, QoSProfile

    from sgim_ros import qos

    role = qos_role(topic, keep_all=keep_all)
    if role == "RECORDS":
        return qos.RECORDS
    if role == "LATEST_STATE":
        return qos.LATEST_STATE
    return QoSProfile(history=HistoryPolicy.KEEP_ALL, depth=1,
                      reliability=qos.LATEST_STATE.reliability,
                      durability=qos.LATEST_STATE.durability)


@dataclass(frozen=True)
class Endpoint:
    """One topic, service or action of a node. `name` is as the node creates it (relative,
    or absolute for a node in its own namespace); `when` says, in words, under which
    condition the node has it (empty: always); `keep_all` keeps every message of a state
    topic (the recorder's)."""

    kind: str
    name: str
    when: str = ""
    keep_all: bool = False

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise UnknownEndpoint(f"{self.name}: kind must be one of {', '.join(KINDS)}, "
                                  f"got {self.kind!r}")
        self.type  # noqa: B018 (refuses a name no table types, at import)

    @property
    def type(self) -> str:
        """The interface type, as 'sgim_msgs/msg/Movement'."""
        bare = self.name.lstrip("/")
        if self.kind in TOPIC_KINDS:
            found = RECORDED_TOPICS.get(bare)
        elif self.kind in ("serves", "calls"):
            found = READY_TYPE if bare.endswith("_ready") else SERVICES.get(_last(bare))
        else:
            found = ACTIONS.get(_last(bare))
        if found is None:
            raise UnknownEndpoint(f"{self.kind} {self.name!r}: no such topic, service or "
                                  "action in sgim_ros/interfaces.py")
        return found

    @property
    def qos(self) -> str:
        """A topic's QoS role (qos_role); '' for a service or an action."""
        return qos_role(self.name, keep_all=self.keep_all) if self.kind in TOPIC_KINDS else ""

    @property
    def conditional(self) -> bool:
        return bool(self.when)

    def interface(self) -> type:
        """The rclpy class of the message, service or action."""
        return ros_message_class(self.type)

    def create(self, node: Any, callback: Callable[..., Any] | None = None, *,
               name: str | None = None, **options: Any) -> Any:
        """Make this endpoint on `node` (the publisher, subscription, service, client or
        action server or client). `name` puts it under a namespaced name that ends with the
        declared one (the arbiter's /NAME/expert_ready); `options` go to rclpy."""
        actual = self.name if name is None else name
        if _last(actual) != _last(self.name):
            raise UnknownEndpoint(f"{actual!r} is not the declared {self.kind} {self.name!r}")
        kind = self.interface()
        if self.kind == "publishes":
            publisher = node.create_publisher(kind, actual, topic_qos(actual), **options)
            from sgim_ros import record_key

            if _last(actual) in record_key.TEACHING_TOPICS:
                return SigningPublisher(publisher, _last(actual), record_key.from_environment())
            return publisher
        if self.kind == "subscribes":
            return node.create_subscription(kind, actual, callback,
                                            topic_qos(actual, keep_all=self.keep_all),
                                            **options)
        if self.kind == "serves":
            from sgim_ros.executors import is_async, serve_async

            service = node.create_service(kind, actual, callback, **options)
            if is_async(callback):  # rclpy 7.1.6's EventsExecutor cannot send its answer
                serve_async(node, service)
            return service
        if self.kind == "calls":
            return node.create_client(kind, actual, **options)
        from rclpy.action import ActionClient, ActionServer

        if self.kind == "action server":
            return ActionServer(node, kind, actual, execute_callback=callback, **options)
        return ActionClient(node, kind, actual, **options)


class SigningPublisher:
    """A publisher of records that teach the learner: each is signed with the run's key
    before it goes out (sgim_ros/record_key.py), whoever publishes it; unsigned when the node
    has no key (started alone). Everything else is the rclpy publisher's."""

    def __init__(self, publisher: Any, topic: str, key: str) -> None:
        self._publisher, self._topic, self._key = publisher, topic, key

    def publish(self, msg: Any) -> None:
        from sgim_ros.record_key import sign_teaching

        self._publisher.publish(sign_teaching(self._topic, msg, self._key))

    def __getattr__(self, name: str) -> Any:
        return getattr(self._publisher, name)


def publishes(name: str, when: str = "") -> Endpoint:
    return Endpoint("publishes", name, when)


def subscribes(name: str, when: str = "", *, keep_all: bool = False) -> Endpoint:
    return Endpoint("subscribes", name, when, keep_all)


def serves(name: str, when: str = "") -> Endpoint:
    return Endpoint("serves", name, when)


def calls(name: str, when: str = "") -> Endpoint:
    return Endpoint("calls", name, when)


def action_server(name: str, when: str = "") -> Endpoint:
    return Endpoint("action server", name, when)


def action_client(name: str, when: str = "") -> Endpoint:
    return Endpoint("action client", name, when)


def declared(*groups: Endpoint | tuple[Endpoint, ...]) -> tuple[Endpoint, ...]:
    """A node's INTERFACES from its own endpoints and its helpers' constants, in the
    reference's order (by kind, then name). An endpoint declared twice is listed once: always
    there if either declaration is unconditional, else under either condition."""
    merged: dict[tuple[str, str, bool], list[str]] = {}
    for group in groups:
        for e in group if isinstance(group, tuple) else (group,):
            merged.setdefault((e.kind, e.name, e.keep_all), []).append(e.when)
    return tuple(sorted((Endpoint(kind, name, "" if "" in whens else " or ".join(
        dict.fromkeys(whens)), keep_all) for (kind, name, keep_all), whens in merged.items()),
        key=lambda e: (KINDS.index(e.kind), e.name)))
