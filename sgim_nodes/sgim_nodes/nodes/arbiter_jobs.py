"""The arbiter's jobs and waits: one action job at a time, and waits on the run's events.

Goal attempts (`reach_goal`) or an imitation (`imitate`) are a ROS action so that the arbiter
can cut it at its next movement boundary when a demonstration or a pause comes: `JobSlot`
holds the running job's handle for that. A job counts only with a known end (succeeded or
cancelled): a result with any other status would add an unknown number of movements, so it
stops the run instead. `Waits` lets the run's coroutine wait, with a deadline, for a condition
that the node's callbacks make true (a teacher's word, an evaluation).
"""

from __future__ import annotations

from collections.abc import Callable

from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient
from rclpy.node import Node
from rclpy.task import Future

from sgim_nodes.nodes.graph_startup import RunAborted
from sgim_ros.entry import first_of

KNOWN_ENDS = (GoalStatus.STATUS_SUCCEEDED, GoalStatus.STATUS_CANCELED)


class JobSlot:
    """The one running job, its handle kept so that it can be cut."""

    def __init__(self, node: Node) -> None:
        self.node = node
        self.handle = None
        self.name = ""

    def cancel(self, only: str | None = None) -> None:
        """Cut the running job (if its name is `only`, when given) at its next boundary."""
        if self.handle is not None and (only is None or self.name == only):
            self.handle.cancel_goal_async()

    async def run(self, client: ActionClient, goal, name: str, movement: int, timeout: float,
                  cut_at_once: bool = False, feedback: Callable[[object], None] | None = None):
        """Send `goal`, wait for its result (RunAborted after `timeout` or on an unknown end)
        and return it; `cut_at_once` cancels it as soon as it is accepted (a demonstration or
        a pause came while it was being sent); `feedback` gets the job's feedback messages."""
        sent = client.send_goal_async(
            goal, feedback_callback=None if feedback is None else
            (lambda message: feedback(message.feedback)))
        if not await first_of(self.node, sent, timeout):
            raise RunAborted(f"'{name}' did not answer a job request in {timeout:g} s")
        handle = sent.result()
        if not handle.accepted:
            raise RunAborted(f"'{name}' refused a job: is another arbiter running?")
        self.handle, self.name = handle, name
        try:
            if cut_at_once:
                handle.cancel_goal_async()
            result_future = handle.get_result_async()
            if not await first_of(self.node, result_future, timeout):
                raise RunAborted(f"no result from the '{name}' job after {timeout:g} s "
                                 f"(call_timeout)")
            response = result_future.result()
        finally:
            self.handle = None
        if response.status == GoalStatus.STATUS_ABORTED:
            raise RunAborted(f"the '{name}' job was aborted by its node at movement "
                             f"{movement}: its log says why")
        if response.status not in KNOWN_ENDS:
            # e.g. unknown: the server no longer knew the job (ros_glue.JOB_RESULT_SECONDS)
            raise RunAborted(f"the '{name}' job at movement {movement} ended with status "
                             f"{response.status}, without a result: its movements are unknown")
        return response.result


class Waits:
    """Conditions the run awaits; `check` (from a callback) releases those now true."""

    def __init__(self, node: Node) -> None:
        self.node = node
        self._waiting: list[tuple[Callable[[], bool], Future]] = []

    def check(self) -> None:
        self._waiting = [(c, f) for c, f in self._waiting if not f.cancelled()]  # timed out
        for condition, future in self._waiting:
            if not future.done() and condition():
                future.set_result(True)
        self._waiting = [(c, f) for c, f in self._waiting if not f.done()]

    async def until(self, condition: Callable[[], bool], timeout: float, what: str) -> None:
        if condition():
            return
        future = Future(executor=self.node.executor)
        self._waiting.append((condition, future))
        if not await first_of(self.node, future, timeout):
            raise RunAborted(f"timed out after {timeout:g} s waiting for {what}")
