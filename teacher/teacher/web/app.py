"""What the web teacher's page asks and what is decided, without ROS and without HTTP.

The node feeds ``WebTeacher`` what the graph says (through its LivePicture and LearnerState);
the HTTP server hands it the page's requests. ``state`` answers the page's polling with only
what changed since the page's last answer (new landings, new evaluations, new log lines; the
regions and teaching goals when their version moved), so a 5000-movement run stays cheap to
follow. ``decide`` turns a page command into the same decisions as the terminal's
(human_commands): a demonstration to send, an action to measure first, a pace request, or a
reply; every refusal is a CommandError whose message the page shows.

Page commands (JSON objects, POST /api/command):
  {"command": "teach", "index": N}           demonstrate teaching-set entry N
  {"command": "offer", "x": X, "y": Y}       the library's most reliable action for (X, Y),
                                             with its outcome: an offer, not yet sent
  {"command": "confirm", "offer": ID}        send that offer
  {"command": "action", "text": "..."}       24 pasted numbers; the outcome is measured first
  {"command": "pace", "what": "pause"|"resume"|"step", "steps": N}
"""

from __future__ import annotations

import itertools
import math
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from sgim_nodes.view.picture import (
    INTEREST_STOPS,
    PROCESS_COLOURS,
    PROCESS_NAMES,
    LivePicture,
)
from teacher.human_commands import (
    CommandError,
    GoalPoint,
    PaceRequest,
    Teach,
    parse_numbers,
    parse_pace,
    parse_unit,
)
from teacher.human_decisions import ExecuteFirst, LearnerState, SendDemonstration, TeachingLibrary

LOG_LINES = 200  # kept for the page
OFFERS_KEPT = 20


@dataclass
class PaceView:
    """The arbiter's pace, as last published (sgim_msgs/PaceState), for the page."""

    paused: bool = False
    held: bool = False  # standing still now (a pause waits for the running job's boundary)
    waiting: bool = False
    steps_left: int = 0
    wait_seconds: float = 0.0
    turn_ends: float = math.inf  # monotonic time the current turn ends (inf: never)
    period: int = 0
    known: bool = False  # false until the arbiter said anything: no pace service yet


class WebTeacher:
    """The page's view of the run and its commands; every method holds ``lock``."""

    def __init__(self, library: TeachingLibrary, picture: LivePicture,
                 state: LearnerState) -> None:
        self.library, self.picture, self.learner = library, picture, state
        self.lock = threading.RLock()
        self.pace = PaceView()
        self.log: deque[tuple[int, str, str]] = deque(maxlen=LOG_LINES)  # (number, level, text)
        self._log_numbers = itertools.count(1)
        self.offers: dict[int, SendDemonstration] = {}
        self._offer_ids = itertools.count(1)
        self.cast = {"version": 0, "caption": "", "rendering": False}

    # --- the log the page shows ------------------------------------------------------------

    def say(self, text: str, level: str = "info") -> None:
        with self.lock:
            self.log.append((next(self._log_numbers), level, text))

    # --- the page's polling ----------------------------------------------------------------

    def state(self, landings: int = 0, evaluations: int = 0, regions: int = -1,
              teaching: int = -1, log: int = 0) -> dict[str, Any]:
        """What changed since the page's cursors (counts it has, versions it drew)."""
        with self.lock:
            pic, learner = self.picture, self.learner
            pic.judge_teaching_goals()
            start = min(max(0, landings), pic.landings)
            if landings > pic.landings:  # the page knows more than we do: a restarted node
                start = 0
            reply: dict[str, Any] = {
                "time": time.time(),
                "learner": pic.learner,
                "count": pic.count,
                "total": pic.total,
                "failed": pic.failed,
                "run": {"state": pic.run_state, "message": pic.run_message,
                        "refusal": learner.refusal()},
                "demonstrations_given": learner.demonstrations,
                "landings": {
                    "from": start,
                    "x": [round(v, 4) for v in pic.xs[start:]],
                    "y": [round(v, 4) for v in pic.ys[start:]],
                    "p": pic.processes[start:],
                },
                "goal": pic.goal,
                "pace": self._pace_json(),
                "cast": dict(self.cast),
            }
            e0 = min(max(0, evaluations), len(pic.evaluations))
            reply["evaluations"] = {"from": e0, "points": pic.evaluations[e0:]}
            if regions != pic.regions_version:
                top = pic.highest_interest()
                reply["regions"] = {
                    "version": pic.regions_version, "top": top,
                    "rects": [[*leaf.low, *leaf.high, round(leaf.interest, 6)]
                              for leaf in pic.leaves]}
            if teaching != pic.teaching_version or teaching < 0:
                reply["teaching"] = {
                    "version": pic.teaching_version,
                    "outcomes": self.library.outcomes.round(4).tolist(),
                    "reached": [bool(r) for r in pic.reached]}
            reply["log"] = [list(line) for line in self.log if line[0] > log]
            reply["demonstrations"] = [
                {"index": d.index, "movement": d.movement_index, "outcome": d.outcome,
                 "teaching_set_index": d.teaching_set_index, "source": d.source,
                 "imitated_from": d.imitated_from, "content": d.content}
                for d in pic.demonstrations[-10:]]
            return reply

    def _pace_json(self) -> dict[str, Any]:
        p = self.pace
        left = p.turn_ends - time.monotonic() if p.waiting else 0.0
        return {"known": p.known, "paused": p.paused, "held": p.held, "waiting": p.waiting,
                "steps_left": p.steps_left, "wait_seconds": p.wait_seconds,
                "wait_left": None if math.isinf(left) else max(0.0, round(left, 1)),
                "period": p.period}

    @staticmethod
    def legend() -> dict[str, Any]:
        """Colours and names the page draws with, from the same tables as the markers."""
        return {"processes": {str(k): {"name": PROCESS_NAMES[k], "rgb": v}
                              for k, v in PROCESS_COLOURS.items()},
                "interest": [[f, rgb] for f, rgb in INTEREST_STOPS]}

    # --- the page's commands ---------------------------------------------------------------

    def decide(self, body: Any) -> SendDemonstration | ExecuteFirst | PaceRequest | dict:
        """A page command to a decision; a dict is a reply to send as it is."""
        if not isinstance(body, dict) or not isinstance(body.get("command"), str):
            raise CommandError("a command must be a JSON object with a 'command' string")
        name = body["command"]
        with self.lock:
            if name == "pace":
                what = body.get("what")
                if what not in ("pause", "resume", "step"):
                    raise CommandError(f"unknown pace command {what!r}: pause, resume or step")
                steps = body.get("steps", 1)
                return parse_pace(what, [str(steps)] if what == "step" else [])
            if name == "teach":
                index = body.get("index")
                if isinstance(index, bool) or not isinstance(index, int):
                    raise CommandError(f"'teach' needs a teaching-set index, got {index!r}")
                return self.library.decide(Teach(index), self.learner)
            if name == "offer":
                point = (parse_unit(body.get("x"), "goal x"), parse_unit(body.get("y"), "goal y"))
                offer = self.library.decide(GoalPoint(point), self.learner)
                number = next(self._offer_ids)
                self.offers[number] = offer
                for old in sorted(self.offers)[:-OFFERS_KEPT]:
                    del self.offers[old]
                distance = float(np.linalg.norm(offer.outcome - np.array(point)))
                return {"ok": True, "message": f"offer {number}: {offer.text}",
                        "offer": {"id": number, "goal": point,
                                  "outcome": [float(v) for v in offer.outcome],
                                  "distance": distance,
                                  "teaching_set_index": offer.teaching_set_index,
                                  "text": offer.text}}
            if name == "confirm":
                number = body.get("offer")
                if number not in self.offers:
                    raise CommandError(f"no offer {number!r} (offers expire after "
                                       f"{OFFERS_KEPT} newer ones): click the point again")
                why = self.learner.refusal()
                if why:
                    raise CommandError(why)
                return self.offers.pop(number)
            if name == "action":
                text = body.get("text")
                if not isinstance(text, str):
                    raise CommandError("'action' needs the pasted numbers as text")
                why = self.learner.refusal()
                if why:
                    raise CommandError(why)
                action = parse_numbers(text, self.library.action_size)
                return ExecuteFirst(action, None, "the pasted action")
        raise CommandError(f"unknown command {name!r}: teach, offer, confirm, action or pace")
