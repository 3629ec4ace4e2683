"""The arbiter's start: wait until every node of the run serves, publishes and listens.

A run that starts before a listener has matched every publisher loses records silently (a late
DDS match; sgim_ros/ready.py), and one that starts before a server is up fails on its first
call. So the arbiter waits, within one deadline, for: the servers it calls, the publishers it
must hear (evaluator, automatic teacher), and each listener's `*_ready` service saying it has
matched every publisher the arbiter sees. Each failure names the node to look at.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

from rclpy.node import Node
from rclpy.task import Future

from sgim_msgs.srv import RecorderReady
from sgim_nodes.core.learner_registry import learner_kind
from sgim_ros.entry import first_of
from sgim_ros.interfaces import RECORDED_TOPICS, Endpoint, calls

POLL_SECONDS = 0.1
READY_CALL_SECONDS = 5.0  # one ready call; a request lost in discovery is asked again


def _ready(service: str, node: str) -> Endpoint:
    return calls(service, f"the run has {node}")


# The `*_ready` service of each node that listens to the run's records, as the arbiter calls it.
RECORDER_READY = _ready("recorder_ready", "the recorder node (or set wait_for_recorder to false)")
EVALUATOR_READY = _ready("evaluator_ready", "the evaluator node")
EXPLORER_READY = _ready("explorer_ready", "the low_level_explorer node")
GOAL_GENERATOR_READY = _ready("goal_generator_ready", "the goal_generator node")
IMITATION_READY = _ready("imitation_ready", "the imitation node")
TEACHER_READY = _ready("teacher_ready", "the teacher node")
EXPERT_READY = calls("expert_ready", "sgim-acts: in the namespace of each of its teachers "
                     "(/NAME/expert_ready)")
WEB_EXPERT_READY = calls("web/expert_ready", "sgim-acts with the web page among its teachers")
READY_CALLS = (RECORDER_READY, EVALUATOR_READY, EXPLORER_READY, GOAL_GENERATOR_READY,
               IMITATION_READY, TEACHER_READY, EXPERT_READY, WEB_EXPERT_READY)


class RunAborted(RuntimeError):
    """The run cannot go on (a node is missing or silent); the message says which."""


@dataclass
class ExpectedGraph:
    """What the run needs before its first movement."""

    servers: list[tuple[object, str]] = field(default_factory=list)  # (client, name)
    publishers: list[str] = field(default_factory=list)  # topics someone must publish
    # (declared ready call, the service's name, who serves it)
    listeners: list[tuple[Endpoint, str, str]] = field(default_factory=list)


def arbiter_graph(learner: str, social: bool, automatic: bool, wait_for_recorder: bool,
                  wait_for_evaluation: bool, *, execute, reach, register,
                  imitate, teachers: Sequence[str] = ()) -> ExpectedGraph:
    """What the arbiter of a `learner` run needs: the servers of its clients (`execute`,
    `reach`, `register`, `imitate`) that this learner calls, the evaluator and the automatic
    teacher heard, and every node that listens to the run's records hearing it from its
    first record (sgim_ros/ready.py); for sgim-acts, the expert of each of its `teachers`
    listening to its requests."""
    kind = learner_kind(learner)
    acts = kind.chooses_teachers
    imitating = kind.imitates and (social or acts)  # demonstrations come or are asked for
    expected = ExpectedGraph(servers=[(execute, "execute_action")])
    if kind.goal_babbling:
        expected.servers.append((reach, "reach_goal"))
        if social or acts:
            expected.servers.append((register, "register_demonstration"))
    if imitating:
        expected.servers.append((imitate, "imitate"))
    # The teacher's checks too: the recorder must have matched their publisher before the
    # first turn, at movement 0 (sgim_ros/ready.py asks only about publishers seen).
    expected.publishers = [topic for needed, topic in ((wait_for_evaluation, "evaluations"),
                                                       (automatic, "demonstrations"),
                                                       (automatic, "teacher_checks"),
                                                       (bool(teachers), "demonstrations"))
                           if needed]
    wanted = [(needed, ready, ready.name, ready.when.removeprefix("the run has "))
              for needed, ready in ((wait_for_recorder, RECORDER_READY),
                                    (wait_for_evaluation, EVALUATOR_READY),
                                    (kind.goal_babbling, EXPLORER_READY),
                                    (kind.goal_babbling, GOAL_GENERATOR_READY),
                                    (imitating, IMITATION_READY), (automatic, TEACHER_READY))]
    wanted += [(True, WEB_EXPERT_READY if f"{name}/expert_ready" == WEB_EXPERT_READY.name
                else EXPERT_READY, f"/{name}/expert_ready", f"the expert node of teacher "
                f"{name} (ros2 run teacher expert --ros-args -r __ns:=/{name})")
               for name in teachers]
    expected.listeners = [(ready, service, who) for needed, ready, service, who in wanted
                          if needed]
    return expected


async def call_bounded(node: Node, client, request, name: str, timeout: float,
                       fatal: bool = True):
    """A service call that gives up after `timeout`: None, or RunAborted naming the service
    when `fatal`."""
    call = client.call_async(request)
    if await first_of(node, call, timeout):
        return call.result()
    client.remove_pending_request(call)
    if fatal:
        raise RunAborted(f"no answer from {name} after {timeout:g} s: is its node running?")
    return None


async def _sleep(node: Node, seconds: float) -> None:
    await first_of(node, Future(), seconds)


async def wait_for_graph(node: Node, expected: ExpectedGraph, timeout: float,
                         settle_time: float) -> None:
    """Return once the graph is complete, then `settle_time` later; RunAborted after
    `timeout` seconds, naming what is missing."""
    deadline = time.monotonic() + timeout
    for client, name in expected.servers:
        ready = getattr(client, "server_is_ready", None) or client.service_is_ready
        while not ready():
            if time.monotonic() > deadline:
                raise RunAborted(f"no '{name}' server after {timeout:g} s: is its node up?")
            await _sleep(node, POLL_SECONDS)
    for topic in expected.publishers:
        while node.count_publishers(topic) < 1:
            if time.monotonic() > deadline:
                raise RunAborted(f"nobody publishes '{topic}' after {timeout:g} s: is its "
                                 "node (evaluator or teacher) up?")
            await _sleep(node, POLL_SECONDS)
    for ready, service, who in expected.listeners:
        await _wait_until_listening(node, ready, service, who, deadline, timeout)
    await _sleep(node, settle_time)


async def _wait_until_listening(node: Node, declared: Endpoint, service: str, who: str,
                                deadline: float, timeout: float) -> None:
    """Ask `service` until it says its node has matched every publisher we see."""
    ready = declared.create(node, name=service)
    name = service.removesuffix("_ready")
    why = f"no {service} service: is {who} up?"
    while time.monotonic() < deadline:
        if ready.service_is_ready():
            request = RecorderReady.Request(topics=list(RECORDED_TOPICS))
            request.publishers = [node.count_publishers(t) for t in RECORDED_TOPICS]
            seconds = min(READY_CALL_SECONDS, max(POLL_SECONDS, deadline - time.monotonic()))
            reply = await call_bounded(node, ready, request, service, seconds, fatal=False)
            if reply is not None and reply.ready:
                node.destroy_client(ready)
                return
            why = (f"the {name} did not answer {service}" if reply is None
                   else f"the {name} is not ready: {reply.message}")
        await _sleep(node, POLL_SECONDS)
    raise RunAborted(f"after {timeout:g} s waiting for {service}, {why}")
