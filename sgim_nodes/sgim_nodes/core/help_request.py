"""When the learner asks the teacher for help (issue 14, ``timing: on-request``).

The paper's teacher interrupts every P movements; its Section III names the alternative, a
learner that asks when it stops making progress, and leaves it to future work. Our rule keeps
the paper's own measure of progress, eq. 2's competence progress over a sliding window of
``window`` (ζ) goals, applied to the learner's whole sequence of goal attempts:

- the learner has *stalled* when, over its last ``window`` own goal attempts (imitations left
  out), the progress |mean(newer half) - mean(older half)| is no larger than ``stall_se``
  standard errors of that difference: no progress that the noise of competences cannot explain;
- it then asks about the goal of the attempt that has just ended (the goal it is trying to
  reach); the teacher answers with the teaching entry whose outcome lies nearest that goal
  among those the learner has not reached (``teaching.Teacher.answer``);
- the ask ends the goal attempt under way, answered or not, as the periodic teacher's turn
  does (the graph's arbiter stops the running job to ask before it knows the answer);
- after an ask, the window starts afresh: ``window`` new attempts before the next ask, so that
  one stall does not spend the budget at once;
- the learner earns one ask every ``period`` movements, as the periodic teacher has one turn
  every P (a first one at movement 0): by movement t it may have asked at most t // P + 1 times,
  and ``budget`` times in all (5000 movements, P = 150: 34), so that the two timings get the
  same number of demonstrations at most, at any time of the run, and comparisons are fair.
  Without this allowance the stall test (which the noise of competences passes at most windows,
  docs/social_modes.md) spent the whole budget in the first fifth of a run.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

PERIOD = "period"
ON_REQUEST = "on-request"
TIMINGS = (PERIOD, ON_REQUEST)
DEFAULT_TIMING = PERIOD
DEFAULT_WINDOW = 20
"""Own goal attempts over which progress is judged: the region tree's ζ when the on-request
rule was built and measured (docs/social_modes.md); kept at 20 when the tree's ζ became 50
(docs/learners.md, section 4c), so the rule and its measurements stay as documented."""
DEFAULT_STALL_SE = 1.0
"""Progress within one standard error of zero counts as none (the same test as the region
tree's optional ``interest_noise_correction`` at c = 1)."""


def check_timing(timing: str) -> str:
    if timing not in TIMINGS:
        raise ValueError(f"unknown timing {timing!r}; choose one of {TIMINGS}")
    return timing


def budget_for(movements: int, period: int) -> int:
    """The periodic teacher's number of turns in a run: the on-request learner's budget."""
    return len(range(0, movements, period))


def progress_and_error(competences: np.ndarray) -> tuple[float, float]:
    """(|mean(newer half) - mean(older half)|, its standard error) of an even-length window."""
    h = len(competences) // 2
    older, newer = competences[:h], competences[h:2 * h]
    gap = abs(float(newer.mean() - older.mean()))
    se = float(np.sqrt((older.var(ddof=1) + newer.var(ddof=1)) / h)) if h >= 2 else 0.0
    return gap, se


@dataclass
class HelpRequests:
    """Ask/tell: ``attempt_ended(competence)`` after each own goal attempt,
    ``should_ask(movements)`` at a movement boundary, ``asked()`` once the question is put."""

    budget: int
    period: int
    window: int = DEFAULT_WINDOW
    stall_se: float = DEFAULT_STALL_SE
    asks: int = 0
    _recent: list[float] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.budget < 0:
            raise ValueError(f"budget must be >= 0, got {self.budget}")
        if self.period < 1:
            raise ValueError(f"period must be >= 1, got {self.period}")
        if self.window < 4 or self.window % 2:
            raise ValueError(f"window must be even and >= 4, got {self.window}")
        if self.stall_se < 0:
            raise ValueError(f"stall_se must be >= 0, got {self.stall_se}")

    def attempt_ended(self, competence: float) -> None:
        self._recent.append(float(competence))
        del self._recent[:-self.window]

    def stalled(self) -> bool:
        if len(self._recent) < self.window:
            return False
        gap, se = progress_and_error(np.asarray(self._recent))
        return gap <= self.stall_se * se

    def allowance(self, movements: int) -> int:
        """How many asks the learner has earned after ``movements`` movements."""
        return min(self.budget, movements // self.period + 1)

    def should_ask(self, movements: int) -> bool:
        return self.asks < self.allowance(movements) and self.stalled()

    def asked(self) -> None:
        """The question was put (answered or not): the window starts afresh."""
        self.asks += 1
        self._recent.clear()
