"""The executors the graph's processes spin on, and what makes rclpy's EventsExecutor safe for
nodes that await.

Why two executors: rclpy's SingleThreadedExecutor rebuilds its wait set in Python at every
wake-up, entity by entity, so a message costs several times what it costs on the
EventsExecutor, and far more when many nodes share one process (shared/notes/rclpy-executors.md;
docs/node_graph.md, "Processes"). The EventsExecutor of the Jazzy wheel (rclpy 7.1.6) has two
gaps that touch nodes which await, each closed here:

- an ``async`` service handler ends in a TypeError in ``send_response`` (ros2/rclpy#1473):
  ``serve_async`` sends its response from a task instead;
- a task awaiting a Future is resumed again and again under ``spin_once`` (a busy loop):
  ``spin_slice`` spins in bounded slices that idle.

tests/ros/test_rclpy_events.py fails if the installed rclpy stops behaving as this relies on.
"""

from __future__ import annotations

import inspect
import os
from collections.abc import Callable, Iterable
from typing import Any

from rclpy.executors import Executor, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.task import Future

EXECUTOR_VARIABLE = "SGIM_EXECUTOR"
EXECUTORS = ("single", "events")


class UnsupportedByEvents(ValueError):
    """A node holds what rclpy's EventsExecutor cannot run (a guard condition)."""


def chosen_kind(kind: str) -> str:
    """`kind` unless ``SGIM_EXECUTOR=single`` puts every process on the SingleThreadedExecutor
    (to compare, or should the EventsExecutor misbehave)."""
    if kind not in EXECUTORS:
        raise ValueError(f"unknown executor {kind!r}: one of {', '.join(EXECUTORS)}")
    return "single" if os.environ.get(EXECUTOR_VARIABLE, "") == "single" else kind


def make_executor(kind: str, nodes: Iterable[Node] = (), context: Any = None) -> Executor:
    """An executor of `kind` ("single" or "events", see `chosen_kind`) holding `nodes`, in
    `context` (rclpy's default when None).

    A node with a guard condition is refused here, in one line, before the EventsExecutor
    would raise "Guard conditions not supported" in the middle of a spin."""
    nodes = list(nodes)
    if chosen_kind(kind) == "single":
        executor: Executor = SingleThreadedExecutor(context=context)
    else:
        for node in nodes:
            if list(node.guards):
                raise UnsupportedByEvents(
                    f"node {node.get_name()} holds a guard condition, which rclpy's "
                    "EventsExecutor cannot run: use the SingleThreadedExecutor")
        from rclpy.experimental import EventsExecutor

        executor = EventsExecutor(context=context)
    for node in nodes:
        executor.add_node(node)
    return executor


def is_events(executor: Executor) -> bool:
    return not isinstance(executor, SingleThreadedExecutor)


def spin_slice(executor: Executor, seconds: float = 0.1) -> None:
    """Run what is ready, waiting at most `seconds`; returns so the caller can check whether
    to stop. On the EventsExecutor it waits on a fresh Future that never completes: its
    ``spin_once`` would resume every awaiting task again and again, and a Future kept across
    calls would gather one done callback per call."""
    if is_events(executor):
        executor.spin_until_future_complete(Future(), timeout_sec=seconds)
    else:
        executor.spin_once(timeout_sec=seconds)


def serve_async(node: Node, service: Any) -> Any:
    """Let `service`, whose handler is a coroutine function, answer on either executor.

    Both executors look ``send_response`` up on the service instance for each request. The
    SingleThreadedExecutor awaits the handler first and passes the response; the
    EventsExecutor passes the coroutine itself. Given a coroutine, the response is sent from
    a task of the node's executor once the coroutine returns it."""
    send = service.send_response

    def send_response(response: Any, header: Any) -> None:
        if not inspect.iscoroutine(response):
            send(response, header)
            return

        async def answer() -> None:
            send(await response, header)

        node.executor.create_task(answer())

    service.send_response = send_response
    return service


def is_async(callback: Callable[..., Any] | None) -> bool:
    return callback is not None and inspect.iscoroutinefunction(callback)
