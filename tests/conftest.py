"""Shared fixtures: an isolated ROS domain per test run and process groups that never leak."""

from __future__ import annotations

import importlib.util
import os
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from sgim_nodes.graph.domain import isolated_ros_environment, reserve_domain
from sgim_nodes.graph.processes import ProcessGroup, group_is_empty

REPO = Path(__file__).resolve().parent.parent
ROS2RUN = str(REPO / "ros_ws" / "ros2run.sh")  # runs a node of the built workspace


def _ros_missing() -> str | None:
    for module in ("rclpy", "sgim_msgs"):
        if importlib.util.find_spec(module) is None:
            return module
    return None


def pytest_configure(config: pytest.Config) -> None:
    """A suite started in the background by a non-interactive shell (`./test.sh &`) inherits
    SIGINT ignored, and so would every process the tests start: the tests that stop a node
    with Ctrl-C would find it deaf. Restore the default, as in a foreground run."""
    import signal

    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object:
    """Workers (`./test.sh`, `-n 2`) take whole files, longest first (tests/scheduling.py)."""
    from tests.scheduling import make_scheduler

    return make_scheduler(config, log)


@pytest.hookimpl(optionalhook=True)
def pytest_handlecrashitem(crashitem: str, report: pytest.TestReport, sched: object) -> None:
    """A test whose worker died fails with the signal that ended it, not only 'crashed'."""
    from tests.scheduling import DEATHS

    death = DEATHS.pop(crashitem, None)
    if death:
        report.longrepr = f"{report.longrepr} ({death}): its worker died in this test"


def pytest_sessionfinish(session: pytest.Session) -> None:
    """A worker hands its fuzz counts to the controller, which prints the summary."""
    workeroutput = getattr(session.config, "workeroutput", None)
    if workeroutput is not None:
        from tests.fuzz.tally import COUNTS

        workeroutput["fuzz_counts"] = {t: dict(c) for t, c in COUNTS.items()}


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node: object, error: object) -> None:
    from tests.fuzz.tally import COUNTS

    for target, counts in getattr(node, "workeroutput", {}).get("fuzz_counts", {}).items():
        COUNTS[target].update(counts)


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """What the fuzz tests tried (tests/fuzz/tally.py), from this process or its workers."""
    from tests.fuzz.tally import COUNTS, summary

    if COUNTS:
        terminalreporter.section("fuzz cases")
        for line in summary():
            terminalreporter.write_line(line)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Skip ROS tests outside the workspace, unless the test command demands ROS."""
    missing = _ros_missing()
    if missing is None:
        return
    if os.environ.get("SGIM_REQUIRE_ROS") == "1":
        raise pytest.UsageError(
            f"SGIM_REQUIRE_ROS=1 but '{missing}' cannot be imported: "
            "run ./bootstrap.sh and source ros_ws/env.sh"
        )
    skip = pytest.mark.skip(reason=f"'{missing}' not importable: source ros_ws/env.sh")
    for item in items:
        if "ros" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def ros_domain() -> Iterator[int]:
    """One ROS domain for the whole test session, discovery kept on this host.

    The pytest process itself joins it, so in-process rclpy nodes and the children started
    through `ros_processes` see each other and nothing else. Under ./test.sh each worker is a
    session of its own, and so has a domain of its own. `./test.sh --quick` starts no graph:
    a test that asks for a domain there lacks its `ros` mark.
    """
    if os.environ.get("SGIM_TEST_QUICK") == "1":
        pytest.fail("./test.sh --quick runs no ROS graph, but this test needs a ROS domain: "
                    "mark it `ros` (pytest.mark.ros)", pytrace=False)
    with reserve_domain() as reservation:
        saved = dict(os.environ)
        os.environ.clear()
        os.environ.update(isolated_ros_environment(reservation.domain_id, saved))
        try:
            yield reservation.domain_id
        finally:
            os.environ.clear()
            os.environ.update(saved)


@pytest.fixture
def ros_processes(ros_domain: int, tmp_path: Path) -> Iterator[ProcessGroup]:
    """Start helper processes in the test's domain; all are stopped and checked gone after."""
    group = ProcessGroup(env=dict(os.environ), log_dir=tmp_path / "logs")
    try:
        yield group
    finally:
        group.stop_all()
        leftovers = [c.pid for c in group.children if not group_is_empty(c.pid)]
        assert not leftovers, f"processes left behind: {leftovers}"


@pytest.fixture
def rclpy_context(ros_domain: int) -> Iterator[object]:
    """An rclpy context of the test process, shut down after the test."""
    import rclpy

    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        yield context
    finally:
        rclpy.try_shutdown(context=context)


PYTHON = sys.executable


LOG_TAIL_LINES = 40
LOG_TAIL_TOTAL = 24_000  # characters of node logs added to one failure report


def node_log_tails(root: Path) -> str:
    """The last lines of every log a failed test's processes wrote under `root` (its own
    logs/ and any run folder's logs/), newest first: on a CI machine the temporary folder is
    gone, so the failure report must carry the nodes' own words."""
    logs = sorted(root.rglob("*.log"), key=lambda p: p.stat().st_mtime, reverse=True)
    parts, total = [], 0
    for log in logs:
        try:
            lines = log.read_text(errors="replace").splitlines()
        except OSError:
            continue
        lines = [line for line in lines if "RTPS_" not in line][-LOG_TAIL_LINES:]
        text = f"== {log.relative_to(root)} (last {len(lines)} lines)\n" + "\n".join(lines)
        if total + len(text) > LOG_TAIL_TOTAL:
            parts.append(f"== ... {len(logs) - len(parts)} more log(s) left out")
            break
        parts.append(text)
        total += len(text)
    return "\n".join(parts)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo) -> Iterator[None]:
    """A failed test that started processes shows their logs in its report."""
    outcome = yield
    report = outcome.get_result()
    tmp_path = getattr(item, "funcargs", {}).get("tmp_path")
    if report.failed and call.when == "call" and isinstance(tmp_path, Path):
        tails = node_log_tails(tmp_path)
        if tails:
            report.sections.append(("node logs", tails))
