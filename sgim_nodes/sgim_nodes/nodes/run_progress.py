"""The arbiter's voice on `run_status`: its states, and its progress every 5 % of the budget.

Why a module of its own: the launcher, the recorder and a human watching the run all read
these messages (the launcher ends a run on FINISHED or ABORTED, the sweep reads the last
progress line), so when and what the arbiter says is one contract, kept apart from how it
drives the run.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from rclpy.node import Node

from sgim_msgs.msg import RunStatus
from sgim_ros.interfaces import publishes

RUN_STATUS = publishes("run_status")  # in the arbiter's INTERFACES


class RunProgress:
    """Publishes RunStatus for `node`; `count` tells the run's movement count when asked."""

    def __init__(self, node: Node, learner: str, seed: int, total: int,
                 count: Callable[[], int]) -> None:
        self.node, self.learner, self.seed, self.total = node, learner, seed, total
        self.count = count
        self.publisher = RUN_STATUS.create(node)
        self.started = time.monotonic()
        self._last_said = 0

    @property
    def step(self) -> int:
        """Movements between two progress reports: 5 % of the budget."""
        return max(1, self.total // 20)

    def due(self, start: int) -> int:
        """Movements a job starting at `start` must make before its report can be said: its
        feedback is asked for only from there (ReachGoal.report_after)."""
        return max(0, self._last_said + self.step - start)

    def moved(self, count: int | None = None) -> None:
        """Every 5 % of the budget: a log line and a RunStatus. `count`: the movements done
        so far when a job under way reports them (its feedback after each goal), since the
        arbiter's own count moves only when a job ends."""
        count = self.count() if count is None else count
        if count <= self._last_said:  # said already (a job's feedback, then its end)
            return
        if count - self._last_said >= self.step or count >= self.total:
            self._last_said = count
            rate = count / max(1e-9, time.monotonic() - self.started)
            self.node.get_logger().info(f"{count}/{self.total} movements "
                                        f"({100 * count / self.total:.0f} %, {rate:.1f}/s)")
            self.say(RunStatus.STATE_RUNNING, "", count)

    def say(self, state: int, message: str, count: int | None = None) -> None:
        """A RunStatus in `state` with `message`, at `count` (default: the run's count)."""
        self.publisher.publish(RunStatus(
            stamp=self.node.get_clock().now().to_msg(), learner=self.learner, seed=self.seed,
            movement_index=self.count() if count is None else count,
            total_movements=self.total, state=state, message=message))
