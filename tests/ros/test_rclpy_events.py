"""What sgim_ros/executors.py and entry.first_of rely on in the installed rclpy.

Each test fails if rclpy stops behaving as the workarounds assume: then review them (a fixed
rclpy may make one unneeded, a changed one may break it)."""

from __future__ import annotations

import contextlib
import statistics
import time
from importlib.metadata import version

import pytest

pytestmark = pytest.mark.ros

rclpy = pytest.importorskip("rclpy")

from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.task import Future  # noqa: E402
from std_srvs.srv import SetBool  # noqa: E402

from sgim_ros.entry import AsyncNode, first_of  # noqa: E402
from sgim_ros.executors import (  # noqa: E402
    UnsupportedByEvents,
    make_executor,
    serve_async,
    spin_slice,
)

KINDS = ("events", "single")


def spin_until(executor, future: Future, limit: float, slice_seconds: float = 0.1) -> None:
    deadline = time.monotonic() + limit
    while not future.done() and time.monotonic() < deadline:
        spin_slice(executor, slice_seconds)


@contextlib.contextmanager
def spinning(context, kind: str, *nodes):
    """`nodes` on an executor of `kind`; the executor is shut down and the nodes destroyed
    after."""
    executor = make_executor(kind, nodes, context)
    try:
        yield executor
    finally:
        executor.shutdown()
        for node in nodes:
            node.destroy_node()


def ready_client(client, executor, service: str):
    """A SetBool client of `service` once it sees the server (at most 10 s)."""
    caller = client.create_client(SetBool, service)
    deadline = time.monotonic() + 10
    while not caller.service_is_ready() and time.monotonic() < deadline:
        spin_slice(executor, 0.05)
    return caller


def names(prefix: str) -> tuple[str, str]:
    stamp = f"{time.monotonic_ns() % 10**9}"
    return f"{prefix}_server_{stamp}", f"{prefix}_client_{stamp}"


class Server(AsyncNode):
    """Answers SetBool with an async handler that itself awaits (as the goal generator does)."""

    def __init__(self, name: str, service: str, context, patched: bool = True) -> None:
        super().__init__(name, context=context)
        made = self.create_service(SetBool, service, self.answer)
        if patched:
            serve_async(self, made)

    async def answer(self, request, response):
        if not request.data:  # wait a little, on a timer, before answering
            await first_of(self, Future(executor=self.executor), 0.002)
        response.success = request.data
        response.message = "answered"
        return response


def test_the_installed_rclpy_is_the_one_the_workarounds_were_checked_on():
    assert version("ros-rclpy") == "7.1.6", (
        "rclpy changed: check the EventsExecutor gaps in sgim_ros/executors.py again "
        "(ros2/rclpy#1473 was fixed in 7.1.11, the busy await in 7.1.9)")


@pytest.mark.parametrize("kind", KINDS)
def test_an_async_handler_answers_through_serve_async(rclpy_context, kind):
    service = f"set_{kind}_{time.monotonic_ns() % 10**9}"
    server_name, client_name = names(kind)
    server = Server(server_name, service, rclpy_context)
    client = Node(client_name, context=rclpy_context)
    with spinning(rclpy_context, kind, server, client) as executor:
        caller = ready_client(client, executor, service)
        for data in (True, False):
            call = caller.call_async(SetBool.Request(data=data))
            spin_until(executor, call, 10.0)
            assert call.done() and call.result().success is data
            assert call.result().message == "answered"


@pytest.mark.filterwarnings("ignore:coroutine .* was never awaited:RuntimeWarning")
def test_an_unpatched_async_handler_still_fails_on_the_events_executor(rclpy_context):
    """ros2/rclpy#1473: if this passes no more, rclpy answers async handlers itself."""
    service = f"set_bug_{time.monotonic_ns() % 10**9}"
    server_name, client_name = names("bug")
    server = Server(server_name, service, rclpy_context, patched=False)
    client = Node(client_name, context=rclpy_context)
    with spinning(rclpy_context, "events", server, client) as executor:
        call = ready_client(client, executor, service).call_async(SetBool.Request(data=True))
        with pytest.raises(TypeError):
            spin_until(executor, call, 5.0)


def test_a_spin_slice_returns_in_time_and_an_awaiting_task_idles(rclpy_context):
    node = AsyncNode(f"idle_{time.monotonic_ns() % 10**9}", context=rclpy_context)
    with spinning(rclpy_context, "events", node) as executor:
        never = Future(executor=executor)

        async def wait_forever() -> None:
            await never

        executor.create_task(wait_forever())
        started = time.monotonic()
        spin_slice(executor, 0.05)
        assert time.monotonic() - started < 2.0  # bounded, however loaded the machine
        cpu, wall = time.process_time(), time.monotonic()
        while time.monotonic() - wall < 1.0:
            spin_slice(executor, 0.1)
        per_second = (time.process_time() - cpu) / (time.monotonic() - wall)
        never.cancel()
        assert per_second < 0.1, f"an awaiting task took {per_second:.2f} s of CPU per second"


def test_first_of_resumes_without_waiting_for_the_next_slice(rclpy_context):
    """Two nodes on one EventsExecutor, a bounded call at a time: with slices of 2 s, a call
    whose awaiting task were left for the next event would take about 2 s."""
    service = f"set_fast_{time.monotonic_ns() % 10**9}"
    server_name, client_name = names("fast")
    server = Server(server_name, service, rclpy_context)
    client = AsyncNode(client_name, context=rclpy_context)
    with spinning(rclpy_context, "events", server, client) as executor:
        caller = ready_client(client, executor, service)
        times: list[float] = []
        done = Future(executor=executor)

        async def calls() -> None:
            for index in range(200):
                started = time.monotonic()
                call = caller.call_async(SetBool.Request(data=index % 4 != 0))
                assert await first_of(client, call, 10.0)
                times.append(time.monotonic() - started)
            done.set_result(True)

        executor.create_task(calls())
        spin_until(executor, done, 120.0, slice_seconds=2.0)
        assert done.done(), f"{len(times)} of 200 calls answered"
        assert max(times) < 1.0, f"slowest call {max(times):.3f} s: an await waited a slice"
        assert statistics.median(times) < 0.05


def test_first_of_gives_up_at_its_timeout(rclpy_context):
    node = AsyncNode(f"late_{time.monotonic_ns() % 10**9}", context=rclpy_context)
    with spinning(rclpy_context, "events", node) as executor:
        pending = Future(executor=executor)
        outcome = Future(executor=executor)

        async def wait() -> None:
            outcome.set_result(await first_of(node, pending, 0.2))

        executor.create_task(wait())
        started = time.monotonic()
        spin_until(executor, outcome, 10.0)
        assert outcome.result() is False and pending.cancelled()
        assert 0.15 < time.monotonic() - started < 5.0


def test_a_node_with_a_guard_condition_is_refused_by_the_events_executor(rclpy_context):
    node = Node(f"guarded_{time.monotonic_ns() % 10**9}", context=rclpy_context)
    guard = node.create_guard_condition(lambda: None)
    try:
        with pytest.raises(UnsupportedByEvents, match="guard condition"):
            make_executor("events", [node], rclpy_context)
        single = make_executor("single", [node], rclpy_context)
        assert isinstance(single, SingleThreadedExecutor)
        single.shutdown()
    finally:
        node.destroy_guard_condition(guard)
        node.destroy_node()
