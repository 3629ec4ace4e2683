"""The entry point every node of the graph shares, the base of nodes that await, and a
bounded await.

A node that cannot start (a bad parameter, an unknown parameter name, an unreadable parameter
file, a missing file) says why in one line and exits with code 2; Ctrl-C and external shutdown
end it cleanly, and it is always destroyed.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.task import Future

from sgim_ros.command_line import check_command_line, read_parameter_file, ros_arguments
from sgim_ros.params import ParameterError


class AsyncNode(Node):
    """A node whose callbacks may `await` (service calls, actions, timers, other messages).

    rclpy runs the callbacks of one mutually exclusive group one at a time, and a coroutine
    that awaits keeps its group busy: with the default group, the reply it awaits could never
    be processed (the deadlock noted in shared/notes/ros2-from-pypi.md). A reentrant default
    group lets other callbacks run while one awaits; with the single-threaded executor they
    still never run in parallel, they only interleave at `await` points.
    """

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name, **kwargs)
        self._default_callback_group = ReentrantCallbackGroup()


async def first_of(node: Node, future: Future, timeout: float) -> bool:
    """Await `future` for at most `timeout` seconds; True if it completed."""
    either = Future(executor=node.executor)

    def finish(value: bool) -> None:
        if not either.done():
            either.set_result(value)

    future.add_done_callback(lambda _: finish(True))
    timer = node.create_timer(timeout, lambda: finish(False))
    try:
        return await either
    finally:
        node.destroy_timer(timer)


def run_node(factory: Callable[[], Node], args: list[str] | None = None,
             refusals: tuple[type[Exception], ...] = ()) -> int:
    """Create and spin one node; a bad parameter ends it with exit code 2 and a clear message.

    Ctrl-C and external shutdown end it cleanly; a node may also end the spin by itself by
    setting `node.finished = True` (with `node.exit_code`). `refusals`: more exceptions that
    mean "cannot start with this configuration".
    """
    argv = sys.argv if args is None else args
    try:
        for path in ros_arguments(argv)[1]:
            read_parameter_file(path)  # rcl reads a file holding a plain string as "nothing"
        rclpy.init(args=args)
    except ParameterError as error:
        print(f"[{factory.__name__}] {error}", file=sys.stderr, flush=True)
        return 2
    except Exception as error:  # rcl's own parse errors (RCLError): one line, not a traceback
        print(f"[{factory.__name__}] {str(error).split(', at /')[0]}", file=sys.stderr,
              flush=True)
        return 2
    node = None
    try:
        node = factory()
        check_command_line(node, argv)
    except (ParameterError, ValueError, FileNotFoundError, *refusals) as error:
        print(f"[{factory.__name__}] {error}", file=sys.stderr, flush=True)
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
        return 2
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        while rclpy.ok() and not getattr(node, "finished", False):
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return int(getattr(node, "exit_code", 0))

