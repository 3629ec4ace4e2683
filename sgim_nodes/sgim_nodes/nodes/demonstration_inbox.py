"""The arbiter's inbox: which demonstrations it accepts, and where each waits for its turn.

Every demonstration is validated first (bag/validation.py: sizes, bounds, a known teaching-set
index). The automatic teacher's word is filed by its boundary (timing `period`) or as the
answer to the learner's ask (`on-request`; a teacher of the other timing is refused). Any other
demonstration (a human teacher's) waits in a queue and cuts the running job, unless the
movement budget is spent. A refusal is said in the log and on run_status, in bursts, so that a
flood of bad demonstrations cannot flood the status topic; the bag keeps them all.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from sgim_msgs.msg import Demonstration
from sgim_nodes.bag.validation import LiveGate

SAID_FIRST = 20  # refusals said one by one; then every SAID_EVERY-th
SAID_EVERY = 100


def shown(demo: Demonstration) -> bool:
    """False for the automatic teacher's "nothing left to show" (empty action and outcome)."""
    return bool(len(demo.action) or len(demo.outcome))


class DemonstrationInbox:
    """Validated demonstrations by where they wait: a boundary's word, an ask's answer (in
    `asks`), or the queue of the human teacher's."""

    def __init__(self, gate: LiveGate, total: int, automatic: bool, asks,
                 warn: Callable[[str], None]) -> None:
        self.gate = gate
        self.total = total
        self.automatic = automatic
        self.asks = asks  # HelpAsks with timing on-request, else None
        self.warn = warn  # says a refusal (log and run_status)
        self.pending: deque[Demonstration] = deque()
        self.boundary_word: dict[int, Demonstration] = {}
        self.refused = 0

    def receive(self, msg: Demonstration, count: int) -> bool:
        """File `msg` arriving after movement `count`; True when it was queued (the running
        job should then be cut at its next movement boundary)."""
        problem = self.gate.check("demonstrations", msg)
        if problem is not None:
            self.refuse(msg, problem.detail)
            return False
        if self.automatic and msg.source == "automatic":
            why = self._file_automatic(msg)
            if why:
                self.refuse(msg, why, always=True)
            return False
        if not shown(msg):
            return False
        if count >= self.total:
            self.refuse(msg, f"it came after the movement budget of {self.total} was spent",
                        always=True)
            return False
        self.pending.append(msg)
        return True

    def _file_automatic(self, msg: Demonstration) -> str:
        """File the automatic teacher's word: at its boundary (period) or as the answer to an
        ask (on-request); '' or why it is refused (a teacher of the other timing)."""
        if self.asks is None:
            if msg.help_request:
                return ("it answers a help request, but this learner's timing is 'period': "
                        "the teacher's timing must be the same")
            self.boundary_word[msg.movement_index] = msg
            return ""
        if not msg.help_request:
            return ("it answers no help request, but this learner's timing is 'on-request': "
                    "the teacher's timing must be the same")
        return self.asks.answered(msg)

    def refuse(self, demo: Demonstration, why: str, always: bool = False) -> None:
        """A demonstration the learner does not take: said in a burst (the first 20 and every
        100th, then a total at the end; one given once the budget was spent, always)."""
        self.refused += 1
        line = f"demonstration {demo.index} ({demo.source}) refused: {why}"
        always = always or demo.movement_index >= self.total  # a late one is always said
        if always or self.refused <= SAID_FIRST or self.refused % SAID_EVERY == 0:
            self.warn(line + f" ({self.refused} refused so far)")

    def refuse_waiting(self) -> None:
        """The budget is spent: every queued demonstration waited in vain."""
        while self.pending:
            self.refuse(self.pending.popleft(), "the movement budget was spent while it "
                        "waited for its turn")
