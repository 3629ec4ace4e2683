"""The arbiter never counts a job whose end it does not know: a result that comes back with
neither "succeeded" nor "cancelled" (say the job server forgot the job, ros_glue's
JOB_RESULT_SECONDS) stops the run with a message naming the job, instead of adding an unknown
number of movements."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from action_msgs.msg import GoalStatus
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.task import Future

from sgim_nodes.nodes.social_interaction import RunAborted, SocialInteraction

pytestmark = pytest.mark.ros


def _done(value) -> Future:
    future = Future()
    future.set_result(value)
    return future


class _Client:
    """A job client whose job is accepted and ends with ``status``."""

    def __init__(self, status: int, movements: int = 3) -> None:
        response = SimpleNamespace(status=status,
                                   result=SimpleNamespace(movements_used=movements))
        self.handle = SimpleNamespace(accepted=True,
                                      get_result_async=lambda: _done(response),
                                      cancel_goal_async=lambda: _done(None))

    def send_goal_async(self, _goal) -> Future:
        return _done(self.handle)


def _run_job(context, status: int) -> tuple[object, int]:
    """Drive SocialInteraction._action on a bare node standing in for the arbiter."""
    node = Node("arbiter_stand_in", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    node.p, node.pending, node.pace, node.count = {"call_timeout": 5.0}, [], None, 10
    node._job = node._job_name = None
    task = executor.create_task(SocialInteraction._action(node, _Client(status), object(),
                                                          "reach_goal"))
    try:
        try:  # rclpy's executor re-raises a task's exception from spin_once
            while not task.done():
                executor.spin_once(timeout_sec=0.1)
            return task.result(), node.count
        except RunAborted as error:
            return error, node.count
    finally:
        executor.shutdown()
        node.destroy_node()


def test_a_job_that_succeeded_counts_its_movements(rclpy_context):
    result, count = _run_job(rclpy_context, GoalStatus.STATUS_SUCCEEDED)
    assert not isinstance(result, RunAborted) and result.movements_used == 3
    assert count == 13


@pytest.mark.parametrize("status", [GoalStatus.STATUS_UNKNOWN, GoalStatus.STATUS_EXECUTING])
def test_a_job_without_a_known_end_stops_the_run_and_counts_nothing(rclpy_context, status):
    error, count = _run_job(rclpy_context, status)
    assert isinstance(error, RunAborted)
    assert "'reach_goal' job at movement 10" in str(error) and f"status {status}" in str(error)
    assert count == 10
