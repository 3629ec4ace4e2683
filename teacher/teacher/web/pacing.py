"""The page's pause and step as the pace service calls they take, counted where the run stands.

Why not one call each: the arbiter counts movements only when a job ends, and a goal attempt
may span many movements. A pause answered with the arbiter's count named a movement the page
had long passed, and a step asked while a job ran was counted from that job's start and ended
where the job did, movements past the step. So here a pause waits until the run stands still
and says the movement it stands at; a step asked while the run moves first pauses it at its
next movement boundary, then steps from there: it makes exactly the movements it was asked
for, from the movement its answer names (the arbiter caps the next job at the step).

``PacePlan`` holds no ROS: the node sends the request it names, hands back each reply as a
``PaceReply``, and gets either the next request or the page's answer.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

SETTLE = 5.0  # seconds a plan waits for the run to stand still (an imitation is never cut)
QUERY_EVERY = 0.05  # seconds between questions while it waits
Answer = dict[str, Any]


@dataclass(frozen=True)
class PaceReply:
    """What a plan needs of the pace service's answer (sgim_msgs/srv/Pace)."""

    accepted: bool
    message: str
    paused: bool
    held: bool  # standing still now: at a pause's boundary, or at a teacher's turn
    movement: int  # the arbiter's count: where the run stands when held
    total: int


@dataclass(frozen=True)
class Request:
    """One call to make: ``command`` 'query', 'pause', 'resume' or 'step'; not before
    ``after`` seconds from the previous reply."""

    command: str
    steps: int = 0
    after: float = 0.0


def movements(n: int) -> str:
    return f"{n} movement{'s' if n != 1 else ''}"


class PacePlan:
    """One page command (pause, resume or step N) from its first call to its answer."""

    def __init__(self, what: str, steps: int, now: float, settle: float = SETTLE) -> None:
        self.what, self.steps = what, int(steps)
        self.deadline = now + settle
        self.stage, self.start = "first", 0

    def first(self) -> Request:
        """A step first asks whether the run stands still; pause and resume go at once."""
        if self.what == "step":
            return Request("query")
        return Request(self.what)

    def next(self, reply: PaceReply, now: float) -> Request | Answer:
        """The next call, or the page's answer."""
        if not reply.accepted:
            return {"ok": False, "message": reply.message}
        if self.what == "resume":
            return {"ok": True, "message": reply.message}
        if self.stage == "step":
            return self._stepping(reply)
        if reply.held:  # standing still: a pause is done, a step counts from here
            if self.what == "pause":
                return {"ok": True, "message": f"paused at movement {reply.movement}"}
            self.stage, self.start = "step", reply.movement
            return Request("step", self.steps)
        if self.stage == "first" and self.what == "step":
            self.stage = "pausing"  # moving: stop at the next boundary, then step
            return Request("pause")
        self.stage = "pausing"
        if not reply.paused:  # someone resumed the run meanwhile
            return {"ok": self.what == "pause", "message": "the run was resumed before it "
                    "stood still" + ("" if self.what == "pause" else ": no step made")}
        if now >= self.deadline:
            if self.what == "pause":
                return {"ok": True, "message": "pausing: the run stops at its next movement "
                        "boundary (an imitation at its end); the page says where"}
            return {"ok": False, "message": "the run is pausing but does not stand still yet "
                    "(an imitation is never cut): step again once it is paused"}
        return Request("query", after=QUERY_EVERY)

    def _stepping(self, reply: PaceReply) -> Answer:
        end = self.start + self.steps
        where = (f"it pauses again at movement {end}" if end < reply.total else
                 f"the run ends at its budget, movement {reply.total}")
        return {"ok": True, "message": f"stepping {movements(self.steps)} from movement "
                f"{self.start}: {where}", "from": self.start}
