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

from sgim_nodes.nodes.arbiter_jobs import JobSlot
from sgim_nodes.nodes.graph_startup import RunAborted

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

    def send_goal_async(self, _goal, feedback_callback=None) -> Future:
        return _done(self.handle)


def _run_job(context, status: int) -> tuple[object, JobSlot]:
    """Drive the arbiter's JobSlot on a bare node standing in for the arbiter."""
    node = Node("arbiter_stand_in", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    slot = JobSlot(node)
    task = executor.create_task(slot.run(_Client(status), object(), "reach_goal", 10, 5.0))
    try:
        try:  # rclpy's executor re-raises a task's exception from spin_once
            while not task.done():
                executor.spin_once(timeout_sec=0.1)
            return task.result(), slot
        except RunAborted as error:
            return error, slot
    finally:
        executor.shutdown()
        node.destroy_node()


def test_a_job_that_succeeded_gives_its_movements(rclpy_context):
    result, slot = _run_job(rclpy_context, GoalStatus.STATUS_SUCCEEDED)
    assert not isinstance(result, RunAborted) and result.movements_used == 3
    assert slot.handle is None  # nothing left to cut


@pytest.mark.parametrize("status", [GoalStatus.STATUS_UNKNOWN, GoalStatus.STATUS_EXECUTING])
def test_a_job_without_a_known_end_stops_the_run_and_gives_no_result(rclpy_context, status):
    error, slot = _run_job(rclpy_context, status)
    assert isinstance(error, RunAborted)
    assert "'reach_goal' job at movement 10" in str(error) and f"status {status}" in str(error)
    assert slot.handle is None
