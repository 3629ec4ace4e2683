"""The base of nodes that await, a bounded await, and how a node's process ends.

How a process starts its nodes is sgim_ros/host.py's. Here: the teardown that no late signal
cuts, the hard end of a node of a run (`end_now`), its profile, and its end when the launcher
dies, however it dies (`follow_launcher`).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import select
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.executors import Executor
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.subscription import Subscription
from rclpy.task import Future

# The launcher passes the read end of a pipe whose write end only it holds: end of file on it
# means the launcher is gone, whatever killed it (SIGKILL included).
LAUNCHER_FD = "SGIM_LAUNCHER_FD"
LAUNCHER_GRACE = 10.0  # seconds to end cleanly after the launcher died, then a hard exit
_PR_SET_PDEATHSIG = 1


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

    # rclpy gives every publisher and subscription default QoS-event handlers (they log an
    # incompatible peer), and its SingleThreadedExecutor rebuilds its wait set in Python, one
    # entity at a time, at every wake-up: in the arbiter they were 12 of the 31 entities. The
    # peer on the other side of an incompatible pair still logs it; ours are left out.
    def create_publisher(self, *args: Any, **kwargs: Any) -> Publisher:
        kwargs.setdefault("event_callbacks", PublisherEventCallbacks(use_default_callbacks=False))
        return super().create_publisher(*args, **kwargs)

    def create_subscription(self, *args: Any, **kwargs: Any) -> Subscription:
        kwargs.setdefault("event_callbacks",
                          SubscriptionEventCallbacks(use_default_callbacks=False))
        return super().create_subscription(*args, **kwargs)


async def first_of(node: Node, future: Future, timeout: float) -> bool:
    """Await `future` for at most `timeout` seconds; True if it completed.

    On the timeout the future is cancelled, which ends the await. The future itself is
    awaited, not a second one completed from its done callback: rclpy's EventsExecutor
    resumes a task when what it awaits completes in the same round of events, and such a
    chain of two left the awaiting task for the next event (up to a spin slice later)."""
    def expire() -> None:
        if not future.done():
            future.cancel()

    timer = node.create_timer(timeout, expire)
    try:
        await future
        return future.done()
    finally:
        node.destroy_timer(timer)


def end_now(code: int) -> None:
    """End a node of a run once it is torn down, without the interpreter's finalization.

    Why: the middleware's participant can spin forever in its destructor at exit (seen after
    a launcher's SIGKILL: a node busy for minutes, its launcher watchdog already stopped with
    the other daemon threads), and such a node holds the run folder's lock, so the run
    cannot be resumed. Everything the node keeps is written by now (the recorder
    closes its bag in destroy_node); only the standard streams are flushed here."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


PROFILE_ENV = "SGIM_PROFILE"
"""A folder: every node started with it set profiles its spin with cProfile and writes
<folder>/<node>.prof (pstats) and <node>.prof.txt (the top functions by own time) when it
ends. benchmarks/bench_graph_vs_runner.py --profile sets it to the run's logs."""


class Profile:
    """cProfile around a node's spin, only when SGIM_PROFILE names a folder.

    It counts the spinning thread's CPU time (time.thread_time), not the wall clock: a node
    waits for messages most of its life, and what costs is the CPU it spends when one comes.
    The .prof.txt's first line also gives the whole process's CPU, so that what the
    middleware's own threads spend (the process's less the spinning thread's) shows too."""

    def __init__(self, name: str) -> None:
        folder = os.environ.get(PROFILE_ENV, "")
        self.path = Path(folder) / f"{name}.prof" if folder else None
        self.profiler = None
        self.process_start = self.process_cpu = 0.0

    def __enter__(self) -> Profile:
        if self.path is not None:
            import cProfile

            self.profiler = cProfile.Profile(time.thread_time)
            self.process_start = time.process_time()
            self.profiler.enable()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.profiler is not None:
            self.profiler.disable()
            self.process_cpu = time.process_time() - self.process_start

    def write(self) -> None:
        if self.profiler is None or self.path is None:
            return
        import io
        import pstats

        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.profiler.dump_stats(self.path)
            text = io.StringIO()
            text.write(f"process CPU while spinning: {self.process_cpu:.3f} s (all threads)\n")
            pstats.Stats(self.profiler, stream=text).sort_stats("tottime").print_stats(40)
            self.path.with_name(self.path.name + ".txt").write_text(text.getvalue())
        except OSError as error:  # a profile must never fail the node
            print(f"[{self.path.stem}] profile not written: {error}", file=sys.stderr,
                  flush=True)


def tear_down(name: str, executor: Executor, nodes: list[Node]) -> None:
    """End the nodes, in this order, whatever signals still come: their own end (the recorder
    closes its bag in destroy_node) must not be cut by a second Ctrl-C or by a
    KeyboardInterrupt that rclpy's signal handler let through late, and rclpy's own teardown
    racing the shutdown that the signal started is no failure of a node: it is said in one
    line, and the exit code stands."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(ValueError, OSError):  # ValueError: not the main thread
            signal.signal(sig, signal.SIG_IGN)
    steps = [("executor shutdown", executor.shutdown),
             *((f"destruction of {node.get_name()}", node.destroy_node) for node in nodes),
             ("rclpy shutdown", rclpy.try_shutdown)]
    for what, step in steps:
        try:
            step()
        except Exception as error:
            print(f"[{name}] {what} after the end: {type(error).__name__}: {error}",
                  file=sys.stderr, flush=True)


def follow_launcher(grace: float = LAUNCHER_GRACE) -> bool:
    """End this process when the launcher that started it dies, whatever the signal.

    The kernel sends SIGINT when the parent dies (PR_SET_PDEATHSIG): the node shuts down as on
    Ctrl-C, and the recorder closes its bag. A watchdog thread reads the launcher's pipe; at
    its end of file it gives the node `grace` seconds to finish, then ends the process hard,
    so a node that hangs on shutdown cannot outlive its run. False when the launcher is
    already gone (it died while this process started): the caller should not start at all.
    """
    try:
        fd = int(os.environ.get(LAUNCHER_FD, ""))
        os.fstat(fd)
    except (ValueError, OSError):
        return True  # not started by the launcher (or the variable without its pipe)
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGINT, 0, 0, 0)
    # Did the launcher die before the signal was armed? Ask without reading: every node of a
    # run holds this same open file description, so its blocking flag is shared, and a node
    # that set it non-blocking for a check could find it set back by another (it then waited
    # for the launcher's end instead of starting). The launcher never writes: the pipe becomes
    # readable only at its end of file.
    readable, _, _ = select.select([fd], [], [], 0)
    if readable and not os.read(fd, 64):
        return False

    def watch() -> None:
        while True:
            try:
                select.select([fd], [], [])  # whatever the shared blocking flag says
                if not os.read(fd, 64):
                    break  # every write end is closed: the launcher is gone
            except (InterruptedError, BlockingIOError):
                continue  # another node read first, or a signal: wait again
            except OSError:
                break
        time.sleep(grace)
        print(f"[{os.getpid()}] still running {grace:g} s after its launcher died: exiting",
              file=sys.stderr, flush=True)
        os._exit(1)

    threading.Thread(target=watch, name="launcher-watchdog", daemon=True).start()
    return True
