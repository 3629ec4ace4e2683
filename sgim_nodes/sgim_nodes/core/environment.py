"""The Environment protocol shared by the planar arm, the fishing world and the ROS bridge.

One protocol for every world means the learners, the evaluator and the runner never know
which simulator they drive.  Only status ``OK`` carries an outcome: a failed movement still
counts as a movement (it cost real time on the robot) but is never stored as an
(action, outcome) pair, because there is no outcome to learn from.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Protocol, runtime_checkable

import numpy as np


class Status(IntEnum):
    """Movement status codes (also used in the ROS messages)."""

    OK = 0
    NO_CONTACT = 1  # timed out without an outcome
    PHYSICS_FAILURE = 2
    INVALID_ACTION = 3


# The Movement.PROCESS_* codes of sgim_msgs by the core's process labels, here so that the
# ROS-free readers of bags (rebuild, analysis) share them with the nodes; a ROS test checks
# them against the message's constants.
PROCESS_CODES = {"goal_directed": 0, "exploration": 1, "imitation": 2, "demonstration": 3,
                 "random": 4, "evaluation": 5}
PROCESS_LABELS = {code: label for label, code in PROCESS_CODES.items()}


class ResultLike(Protocol):
    """What ``execute`` returns: ``outcome`` is only meaningful when ``status == 0``."""

    outcome: np.ndarray | None
    status: int


@dataclass(frozen=True)
class MovementResult:
    """Concrete result type; any object with ``.outcome`` and ``.status`` is accepted."""

    outcome: np.ndarray | None
    status: int = Status.OK

    @property
    def ok(self) -> bool:
        return self.status == Status.OK and self.outcome is not None


@runtime_checkable
class Environment(Protocol):
    """A world that executes one action in [-1, 1]^action_dim and reports its outcome."""

    action_dim: int
    outcome_dim: int

    def execute(self, action: np.ndarray) -> ResultLike: ...


def is_success(result: ResultLike) -> bool:
    """True when a result carries a usable outcome (status OK and an outcome present)."""
    return int(result.status) == Status.OK and result.outcome is not None
