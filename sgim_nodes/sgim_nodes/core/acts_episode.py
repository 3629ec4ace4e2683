"""One SGIM-ACTS episode once its (strategy, goal) is chosen: what the learner asks, what a
teacher's answer makes it do, and what it folds, the same rules for both hosts.

SgimActsLearner (acts_learner.py) carries the steps out itself, movement by movement; the
graph's arbiter (nodes/acts_episodes.py) translates each into ROS: the request on
`help_requests`, the registration in the explorer's memory, an imitation job or a goal job.

- A mimicry request asks for the demonstration's action and outcome, an emulation request
  for its outcome only (what the teacher shows).
- An answer without what the strategy needs ("none there") ends the episode at once, with no
  movement and nothing reached: competence -1 at the chosen goal.
- Mimicry stores the shown pair when the teacher's cast landed, then imitates its action
  ``imitation_count`` times; emulation attempts the shown outcome as a goal, its action never
  known.
- The episode's competence is measured at the goal the learner chose, from the outcome
  nearest it over the episode's movements, against memory's distance to it when chosen; an
  episode the movement budget cuts short folds nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .strategies import MIMICRY
from .teaching import GOAL_ONLY, MEANS_AND_GOAL

NONE_THERE, IMITATE, EMULATE = "none there", "imitate", "emulate"
MAX_REQUESTS_IN_A_ROW = 10_000
"""Requests without a movement after which a run stops: only a learner without the
autonomous strategy whose teachers all answer "none there" gets there (else it would loop)."""


def request_content(kind: str) -> str:
    """What a request of this strategy kind asks to be shown (core/teaching.py contents)."""
    return MEANS_AND_GOAL if kind == MIMICRY else GOAL_ONLY


@dataclass(frozen=True)
class Step:
    """What the learner does with an answer: NONE_THERE, IMITATE ``action`` ``repetitions``
    times (storing it with ``outcome`` first when the cast landed), or EMULATE (attempt
    ``outcome`` as a goal)."""

    kind: str
    action: np.ndarray | None = None
    outcome: np.ndarray | None = None
    repetitions: int = 0

    @property
    def stores(self) -> bool:
        """Whether the shown (action, outcome) pair enters memory, as SGIM-D stores one."""
        return self.kind == IMITATE and self.outcome is not None


def after_answer(kind: str, action: np.ndarray | None, outcome: np.ndarray | None,
                 imitation_count: int) -> Step:
    """The step an answer showing ``action`` and ``outcome`` (None: not shown) starts for a
    social strategy of ``kind``."""
    usable = action is not None if kind == MIMICRY else outcome is not None
    if not usable:
        return Step(NONE_THERE)
    if kind == MIMICRY:
        return Step(IMITATE, action, outcome, imitation_count)
    return Step(EMULATE, None, outcome)


def folds(step: Step, movements_made: int) -> bool:
    """Whether the episode's competence is folded once its step made ``movements_made``
    movements: always for "none there"; for an imitation, when it made all its repetitions
    (the budget did not cut it). An emulation's goal attempt folds as any goal attempt."""
    return step.kind != IMITATE or movements_made == step.repetitions
