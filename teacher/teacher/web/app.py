"""What the web teacher's page asks and what is decided, without ROS and without HTTP.

The node feeds ``WebTeacher`` what the graph says (through its LivePicture and LearnerState);
the HTTP server hands it the page's requests. ``state`` answers the page's polling with only
what changed since the page's last answer (new landings, new evaluations, new log lines; the
regions and teaching goals when their version moved), so a 5000-movement run stays cheap to
follow. ``decide`` turns a page command into the same decisions as the terminal's
(human_commands): a demonstration to send, an action to measure first, a pace request, or a
reply; every refusal is a CommandError whose message the page shows.

``command`` carries one out: the commands that demonstrate need an idempotency ``key``
(a repeat of a request, a double click or a retry, is refused with the first answer) and go
one at a time: none while another is on its way or while the learner has not finished
imitating the previous one (a demonstration cuts the imitation under way short), so twenty
clicks give one demonstration. Any JSON at all is answered with a decision or a refusal.

After the run, the page stays (``Linger``) while a person looks at it, for at most the node's
``linger`` seconds, or until they close it.

Page commands (JSON objects, POST /api/command):
  {"command": "teach", "index": N, "key": K}     demonstrate teaching-set entry N
  {"command": "offer", "x": X, "y": Y}           the library's most reliable action for
                                                 (X, Y), with its outcome: an offer, not sent
  {"command": "confirm", "offer": ID, "key": K}  send that offer
  {"command": "action", "text": "...", "key": K} 24 pasted numbers; the outcome is measured
  {"command": "pace", "what": "pause"|"resume"|"step", "steps": N}
  {"command": "close"}                           the run is over: stop serving the page
  {"command": "none"}                            SGIM-ACTS asked (the web teacher is one of
                                                 its experts): nothing to show near its goal
"""

from __future__ import annotations

import itertools
import math
import re
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from sgim_nodes.core.environment import PROCESS_CODES
from sgim_nodes.core.learner_registry import display_name
from sgim_nodes.view.picture import (
    INTEREST_STOPS,
    PROCESS_COLOURS,
    PROCESS_NAMES,
    LivePicture,
)
from sgim_ros.clip import clipped, value_text
from sim_bridge.scaling import OUTCOME_BOX
from teacher.human_commands import (
    CommandError,
    GoalPoint,
    NoneThere,
    PaceRequest,
    Teach,
    parse_numbers,
    parse_pace,
    parse_unit,
)
from teacher.human_decisions import ExecuteFirst, LearnerState, SendDemonstration, TeachingLibrary

LOG_LINES = 200  # kept for the page
OFFERS_KEPT = 20
DEMONSTRATING = frozenset({"teach", "confirm", "action"})  # the commands that need a key
KEY = re.compile(r"[A-Za-z0-9_-]{8,64}")
KEYS_KEPT = 1000  # answered requests remembered, to recognise their repeats
LOOKING = 90.0  # seconds since a page last asked for the state: someone is looking at it
IMITATION = PROCESS_CODES["imitation"]
LANDING_PROCESSES = ("goal_directed", "exploration", "imitation", "random")  # drawn as dots
# The page's marks other than landings, distinct from the landings' colours and each other.
MARK_COLOURS = {"unreached": (230, 40, 40), "reached": (0, 150, 136), "goal": (0, 0, 0),
                "offer": (106, 27, 154), "demonstration": (230, 0, 170), "shore": (40, 70, 110)}
# The lake under it all (the node's lake.png): strong enough to stay apart under the shading.
WATER_RGB = (150, 195, 235)
LAND_RGB = (232, 214, 168)
Answer = dict[str, Any]


MESSAGE_LIMIT = 300
"""The longest message the page shows in one line."""


def learner_title(name: str) -> str:
    """How the page names the learner (RunStatus.learner), as its declaration says; '' while
    no run said it."""
    return display_name(name) if name else name


def outcome_space() -> dict[str, Any]:
    """What the page's axes need: the outcome box in metres of the world (sim_bridge's
    OUTCOME_BOX: x forward from the robot, y to its left) that [-1, 1]^2 maps onto."""
    return {"box": [float(v) for v in OUTCOME_BOX], "unit": "m",
            "x": "forward from the robot", "y": "to the robot's left"}


def shown(value: Any, limit: int = 60) -> str:
    """A value sent by a client, for a message: its repr, cut short."""
    return value_text(value, limit)


@dataclass
class Imitation:
    """The latest demonstration sent, until the learner has imitated it to its end."""

    number: int
    movement: int  # the count when it was sent
    seen: int = 0  # imitation movements since

    def over_after(self, index: int, process: int) -> bool:
        """Whether movement ``index`` shows the imitation ended (or never began: refused).
        The movement right after the sending may still be the job it cancelled."""
        if index <= self.movement:
            return False
        if process == IMITATION:
            self.seen += 1
            return False
        return bool(self.seen) or index >= self.movement + 2


@dataclass
class Linger:
    """After the run: the page keeps its final state for a person who looks at it."""

    decided: bool = False
    until: float | None = None  # monotonic end while it lingers
    closed: bool = False  # the person closed it, or its time ran out

    def left(self, now: float) -> float | None:
        if self.until is None or self.closed:
            return None
        return max(0.0, self.until - now)


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
        self.expert = ""  # the name SGIM-ACTS asks it by (web_expert.py); "": it teaches freely
        self.lock = threading.RLock()
        self.pace = PaceView()
        self.log: deque[tuple[int, str, str]] = deque(maxlen=LOG_LINES)  # (number, level, text)
        self._log_numbers = itertools.count(1)
        self.offers: dict[int, SendDemonstration] = {}
        self._offer_ids = itertools.count(1)
        self.cast = {"version": 0, "caption": "", "rendering": False}
        self.keys: OrderedDict[str, str] = OrderedDict()  # key -> its answer ("": on its way)
        self.on_its_way: str | None = None  # the key of the demonstration being carried out
        self.imitation: Imitation | None = None
        self.last_look = -math.inf  # monotonic time a page last asked for the state
        self.linger = Linger()

    # --- the log the page shows ------------------------------------------------------------

    def say(self, text: str, level: str = "info") -> None:
        with self.lock:
            self.log.append((next(self._log_numbers), level, text))

    # --- the page's polling ----------------------------------------------------------------

    def state(self, landings: int = 0, evaluations: int = 0, regions: int = -1,
              teaching: int = -1, log: int = 0) -> dict[str, Any]:
        """What changed since the page's cursors (counts it has, versions it drew)."""
        with self.lock:
            now = time.monotonic()
            self.last_look = now
            pic, learner = self.picture, self.learner
            pic.judge_teaching_goals()
            start = min(max(0, landings), pic.landings)
            if landings > pic.landings:  # the page knows more than we do: a restarted node
                start = 0
            reply: dict[str, Any] = {
                "time": time.time(),
                "learner": pic.learner,
                "learner_title": learner_title(pic.learner),
                "count": pic.count,
                "total": pic.total,
                "failed": pic.failed,
                "run": {"state": pic.run_state, "message": pic.run_message,
                        "refusal": learner.refusal()},
                "demonstrations_given": learner.demonstrations,
                "expert": self.expert,
                "landings": {
                    "from": start,
                    "x": [round(v, 4) for v in pic.xs[start:]],
                    "y": [round(v, 4) for v in pic.ys[start:]],
                    "p": pic.processes[start:],
                },
                "goal": pic.goal,
                "pace": self._pace_json(),
                "cast": dict(self.cast),
                "linger": {"left": self.linger.left(now), "closed": self.linger.closed},
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
        """Colours and names the page draws with: the landings' from the markers' tables (only
        processes whose movements land: a demonstration's measuring cast is never one), the
        other marks' own, all distinct."""
        codes = [PROCESS_CODES[name] for name in LANDING_PROCESSES]
        return {"processes": {str(k): {"name": PROCESS_NAMES[k], "rgb": PROCESS_COLOURS[k]}
                              for k in codes},
                "marks": {name: list(rgb) for name, rgb in MARK_COLOURS.items()},
                "lake": {"water": list(WATER_RGB), "land": list(LAND_RGB)},
                "interest": [[f, rgb] for f, rgb in INTEREST_STOPS],
                "space": outcome_space()}

    # --- what the node hears ---------------------------------------------------------------

    def movement_seen(self, index: int, process: int) -> None:
        with self.lock:
            if self.imitation is not None and self.imitation.over_after(index, process):
                self.imitation = None

    def demonstration_sent(self, number: int, movement: int) -> None:
        with self.lock:
            self.imitation = Imitation(number, movement)

    def run_ended(self, seconds: float) -> bool:
        """The run is over: whether the page stays, for ``seconds`` at most. Only while
        someone looks at it: a run nobody watches (a script) ends as it did."""
        with self.lock:
            if self.linger.decided:
                return self.linger.until is not None
            self.linger.decided = True
            now = time.monotonic()
            if seconds > 0 and now - self.last_look <= LOOKING:
                self.linger.until = now + seconds
                self.say(f"the run is over: this page keeps its final state for {seconds:g} s, "
                         "or until you close it", "turn")
                return True
            return False

    def linger_ended(self) -> bool:
        """Whether a lingering page's time ran out or the person closed it (once true, it
        stays true)."""
        with self.lock:
            linger = self.linger
            if linger.until is None:
                return False
            if not linger.closed and time.monotonic() >= linger.until:
                linger.closed = True
            return linger.closed

    # --- the page's commands ---------------------------------------------------------------

    def command(self, body: Any, carry_out: Callable[[Any], Answer]) -> Answer:
        """Answer one page command; ``carry_out`` (the node's) sends or measures a decision
        and returns the answer. Every refusal is said in the page's log too."""
        try:
            decision, key = self._admit(body)
        except CommandError as error:
            message = clipped(str(error), MESSAGE_LIMIT)
            self.say(f"refused: {message}", "error")
            return {"ok": False, "message": message}
        if isinstance(decision, dict):
            self.say(decision["message"])
            return decision
        answer: Answer = {"ok": False, "message": "the command was not carried out"}
        try:
            answer = carry_out(decision)
        finally:
            with self.lock:
                if key is not None:
                    self.on_its_way = None
                    self.keys[key] = str(answer.get("message", ""))
        return answer

    def _admit(self, body: Any) -> tuple[Any, str | None]:
        """The decision, and the key it was admitted under if it demonstrates."""
        with self.lock:
            name = body.get("command") if isinstance(body, dict) else None
            if not isinstance(name, str) or name not in DEMONSTRATING:
                return self.decide(body), None
            key = body.get("key")
            if not isinstance(key, str) or not KEY.fullmatch(key):
                raise CommandError(f"'{name}' needs a 'key' (8 to 64 letters, digits, - or _, "
                                   f"new for each request), got {shown(key)}: reload the page")
            if key in self.keys:
                first = self.keys[key]
                raise CommandError(f"repeated request ignored (key {key}): " + (
                    f"it was answered: {first}" if first else "it is being carried out"))
            why = self._busy()
            if why:
                raise CommandError(why)
            decision = self.decide(body)
            self.keys[key] = ""
            while len(self.keys) > KEYS_KEPT:
                self.keys.popitem(last=False)
            self.on_its_way = key
            return decision, key

    def _busy(self) -> str:
        """Why no demonstration can be sent now, or ''."""
        if self.on_its_way is not None:
            return "a demonstration is on its way: wait for its answer"
        if self.imitation is not None:
            i = self.imitation
            return (f"demonstration {i.number} (sent at movement {i.movement}) is not imitated "
                    "to its end yet, and another one now would cut it short: wait a few "
                    "movements (resume the run if it is paused)")
        return ""

    def decide(self, body: Any) -> SendDemonstration | ExecuteFirst | PaceRequest | dict:
        """A page command to a decision; a dict is a reply to send as it is."""
        if not isinstance(body, dict) or not isinstance(body.get("command"), str):
            raise CommandError("a command must be a JSON object with a 'command' string")
        name = body["command"]
        with self.lock:
            if name == "pace":
                what = body.get("what")
                if not isinstance(what, str) or what not in ("pause", "resume", "step"):
                    raise CommandError(f"unknown pace command {shown(what)}: pause, resume or "
                                       "step")
                steps = body.get("steps", 1)
                if what == "step" and not is_integer(steps):
                    raise CommandError(f"'step' needs a whole number of movements, got "
                                       f"{shown(steps)}")
                return parse_pace(what, [str(steps)] if what == "step" else [])
            if name == "teach":
                index = body.get("index")
                if not is_integer(index):
                    raise CommandError(f"'teach' needs a teaching-set index, got {shown(index)}")
                return self.library.decide(Teach(index), self.learner)
            if name == "offer":
                point = (unit(body.get("x"), "goal x"), unit(body.get("y"), "goal y"))
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
                if not is_integer(number) or number not in self.offers:
                    raise CommandError(f"no offer {shown(number)} (offers expire after "
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
            if name == "close":
                return self._close()
            if name == "none":
                return NoneThere()
        raise CommandError(f"unknown command {shown(name)}: teach, offer, confirm, action, "
                           "pace, none or close")

    def _close(self) -> dict:
        if not (self.picture.over or self.learner.run_over):
            raise CommandError("the run is still going: the page closes once it is over "
                               "(Ctrl-C at the terminal stops the run)")
        if self.linger.until is None:
            return {"ok": True, "message": "nothing keeps this page: it ends with the run"}
        self.linger.closed = True
        return {"ok": True, "message": "closed: the web teacher stops in a moment; this page "
                "keeps what it shows"}


def is_integer(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def unit(value: Any, what: str) -> float:
    """A JSON number in [-1, 1] (parse_unit's checks; an integer too large for a float is
    refused here, not by float()'s OverflowError)."""
    if is_integer(value) and abs(value) > 1:
        raise CommandError(f"{what} = {shown(value)} is outside [-1, 1]")
    if not isinstance(value, int | float):
        raise CommandError(f"{what} is {shown(value)}, not a number")
    return parse_unit(value, what)
