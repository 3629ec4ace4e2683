"""The learner's schedule, one object for both hosts: when the automatic teacher takes its
turn, when the learner asks for help, and how far the learner's own work may go before the
next of these. The single-process runner asks it before every movement; the graph's arbiter
asks it before every job and caps the job where the schedule says the next event comes, so
that both hosts interrupt the learner at the same movements.

The rules themselves are the paper's and ours: the teacher is due at movements 0, P, 2P, ...
(teaching.Teacher); on request, the learner asks when its progress stalls and it has earned
an ask (help_request.HelpRequests), about the goal of its latest own goal attempt, and the ask
ends the attempt under way, which is folded into the rule's window only after the question is
put (a goal attempt the ask did not cut is folded at once).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from .help_request import ON_REQUEST, HelpRequests, budget_for, check_timing


@dataclass(frozen=True)
class Ask:
    """A question the learner puts: its index (from 1), the movement it is put at, and the
    goal of its latest own goal attempt (None before the first)."""

    index: int
    movement: int
    goal: np.ndarray | None


class Schedule:
    """Ask/tell over a run's ``budget`` of movements. ``teacher``: an automatic teacher speaks
    to this learner; it takes its turn every ``period`` movements, or, with ``timing``
    on-request, answers the learner's asks (at most as many as it would have had turns)."""

    def __init__(self, budget: int, period: int, timing: str, teacher: bool) -> None:
        check_timing(timing)
        if budget < 0 or period < 1:
            raise ValueError(f"a schedule needs budget >= 0 and period >= 1, got {budget} and "
                             f"{period}")
        self.budget = budget
        self.period = period
        on_request = teacher and timing == ON_REQUEST
        self.turn_period = period if teacher and not on_request else 0
        self.help = HelpRequests(budget_for(budget, period), period) if on_request else None
        self.turns_taken: set[int] = set()
        self.last_goal: np.ndarray | None = None  # of the latest own goal attempt folded
        self._cut: tuple[np.ndarray, float] | None = None  # an attempt an ask interrupts

    # --- the teacher's turns -------------------------------------------------------------
    def turn_due(self, count: int) -> bool:
        """The teacher's turn is at this movement boundary and was not taken yet."""
        return (bool(self.turn_period) and count < self.budget
                and count % self.turn_period == 0 and count not in self.turns_taken)

    def take_turn(self, count: int) -> None:
        self.turns_taken.add(count)

    # --- the learner's asks ----------------------------------------------------------------
    def ask_due(self, count: int) -> bool:
        """A stalled learner that has earned an ask puts it at this boundary."""
        if self.help is None:
            return False
        if self._cut is not None and not self.help.should_ask(count):
            self._fold(*self._cut)  # cut by the budget's end or a job's, not by an ask
            self._cut = None
        return self.help.should_ask(count)

    def ask(self, count: int) -> Ask:
        """Put the question: the rule's window starts afresh, and an attempt the ask cut is
        folded into the new window."""
        goal = self.last_goal
        self.help.asked()
        if self._cut is not None:
            self._fold(*self._cut)
            self._cut = None
        return Ask(self.help.asks, count, None if goal is None else goal.copy())

    def attempt_ended(self, goal: np.ndarray, competence: float,
                      cut_at: int | None = None) -> None:
        """An own goal attempt's competence; ``cut_at``: the movement boundary where the host
        cut it, None when it ended by itself (an imitation never comes here)."""
        if self.help is None:
            self.last_goal = np.asarray(goal, dtype=float)
        elif cut_at is not None and self.help.should_ask(cut_at):
            self._cut = (np.asarray(goal, dtype=float), float(competence))  # after the ask
        else:
            self._fold(goal, competence)

    def _fold(self, goal: np.ndarray, competence: float) -> None:
        self.help.attempt_ended(competence)
        self.last_goal = np.asarray(goal, dtype=float)

    # --- a resumed run ------------------------------------------------------------------
    def resume(self, count: int, turns_taken: Iterable[int],
               asks: Iterable[tuple[int, np.ndarray]],
               attempts: Iterable[tuple[int, np.ndarray, float]]) -> None:
        """Where a run stopped at movement ``count`` left the schedule, from its records: the
        teacher's turns taken, the asks put ((movement, goal) in order) and the own goal
        attempts ((movement, goal, competence) in order, imitations left out).

        An attempt that ends where the last ask was put went into the window before the ask
        if it ended by itself, after it if the ask cut it; the ask's goal tells which, since
        it is the goal of the latest attempt folded before the ask. One case stays open: a run
        stopped right where an ask was due, before it was put, whose last attempt the ask
        would have cut is folded as if it had ended by itself."""
        self.turns_taken = set(turns_taken)
        if self.help is None:
            return
        put = [(m, np.asarray(g, dtype=float)) for m, g in asks if m < count]
        self.help.asks = len(put)
        last = put[-1] if put else None
        own = [(m, np.asarray(g, dtype=float), float(c)) for m, g, c in attempts if m <= count]
        for movement, goal, competence in own:
            if last is None or movement > last[0] or (
                    movement == last[0] and not np.allclose(goal, last[1])):  # the ask cut it
                self.help.attempt_ended(competence)
        if own:
            self.last_goal = own[-1][1]

    # --- how far the learner's own work may go ------------------------------------------
    def cap(self, count: int) -> int:
        """Movements the next job may make: to the budget, the teacher's next turn, or the
        movement where a stalled learner that has used every ask earned so far earns its next
        one."""
        cap = self.budget - count
        if self.turn_period:
            cap = min(cap, self.turn_period - count % self.turn_period)
        rule = self.help
        if (rule is not None and rule.stalled() and rule.asks < rule.budget
                and rule.asks >= rule.allowance(count)):
            cap = min(cap, (count // self.period + 1) * self.period - count)
        return cap
