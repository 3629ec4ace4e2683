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


def _ros_missing() -> str | None:
    for module in ("rclpy", "sgim_msgs"):
        if importlib.util.find_spec(module) is None:
            return module
    return None


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
    through `ros_processes` see each other and nothing else.
    """
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
