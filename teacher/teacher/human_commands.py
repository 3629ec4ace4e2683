"""The human teacher's command language, without ROS: parsing, validation and decisions.

Kept free of rclpy so that every bad-input case is unit-tested in milliseconds; the node only
feeds it what it hears (movements, evaluations), sends what it decides and prints its text.
A person at a terminal types anything: every mistake becomes a ``CommandError`` whose message
names the problem, never a traceback.

Commands (``help`` prints this list):
  list          teaching-set goals the learner has not reached within the tolerance, numbered
  status        latest evaluation error, movement count, demonstrations given
  teach N       send teaching-set entry N as a demonstration
  goal X Y      offer the library's most reliable (action, outcome) pair for the goal (X, Y),
                saying how far its outcome is from the goal; ``send`` demonstrates it
  yaml FILE     send the 24 action parameters of FILE; the outcome comes from executing them
                once through the simulator's execute_action service with record=false (not a
                learner movement), so a person never has to guess it; an ``outcome: [x, y]``
                in the file is only a fallback for when that service is not available
  pause, resume, step [N]   pace the run through the arbiter's ``pace`` service; ``resume``
                at a teacher turn goes on without a demonstration
  help, quit

What the node decides from a command (and what it has heard) is in human_decisions.py.
"""

from __future__ import annotations

import math
import shlex
from dataclasses import dataclass
from typing import Any

import numpy as np

OUTCOME_SIZE = 2

HELP = """commands:
  list          teaching-set goals not reached yet (within the tolerance), with their outcome
  status        latest evaluation error, movement count, demonstrations given
  teach N       send teaching-set entry N (see list) as a demonstration
  goal X Y      offer the library's most reliable action for the goal point (X, Y) in
                [-1, 1]^2, with the outcome it gives and how far that is from the goal
  send          demonstrate the last offer (goal X Y)
  yaml FILE     send the action in FILE (a list of 24 numbers in [-1, 1], or `action: [...]`);
                its outcome is measured by executing it once through execute_action (not
                recorded); a file's `outcome: [x, y]` is used only if that service is absent
  pause         pause the run before its next movement
  resume        go on (at your turn: go on without a demonstration)
  step [N]      make N movements (default 1), then pause again
  help          this list
  quit          leave (end of input and Ctrl-C also leave)"""


class CommandError(ValueError):
    """A line that cannot be obeyed; the message says why, for the person who typed it."""


@dataclass(frozen=True)
class NoneThere:
    """SGIM-ACTS asked this teacher (teacher/web_expert.py) and the person has nothing to
    show near its goal: an empty answer to its oldest request."""


# --- parsed commands ---------------------------------------------------------------------


@dataclass(frozen=True)
class Help:
    pass


@dataclass(frozen=True)
class Quit:
    pass


@dataclass(frozen=True)
class ListGoals:
    pass


@dataclass(frozen=True)
class Status:
    pass


@dataclass(frozen=True)
class Teach:
    index: int


@dataclass(frozen=True)
class GoalPoint:
    point: tuple[float, ...]


@dataclass(frozen=True)
class Send:
    """Demonstrate the last offer made for a goal point (the person confirms it)."""


@dataclass(frozen=True)
class YamlFile:
    path: str


@dataclass(frozen=True)
class PaceRequest:
    """pause, resume or step: for the arbiter's pace service."""

    what: str  # "pause", "resume" or "step"
    steps: int = 0


Command = Help | Quit | ListGoals | Status | Teach | GoalPoint | Send | YamlFile | PaceRequest

_NO_ARGUMENT = {"help": Help, "?": Help, "quit": Quit, "exit": Quit, "list": ListGoals,
                "status": Status, "send": Send}
PACE_WORDS = ("pause", "resume", "step")


def parse(line: str) -> Command | None:
    """One typed line to a command; None for a blank line."""
    try:
        words = shlex.split(line)
    except ValueError as error:  # "No closing quotation"
        raise CommandError(f"cannot read the line: {error}") from None
    if not words:
        return None
    name, args = words[0].lower(), words[1:]
    if name in _NO_ARGUMENT:
        if args:
            raise CommandError(f"'{name}' takes no arguments, got {len(args)}")
        return _NO_ARGUMENT[name]()
    if name == "teach":
        if len(args) != 1:
            raise CommandError(f"'teach' needs one teaching-set index (e.g. teach 3), "
                               f"got {len(args)} values")
        return Teach(parse_index(args[0]))
    if name == "goal":
        if len(args) != OUTCOME_SIZE:
            raise CommandError(f"'goal' needs {OUTCOME_SIZE} numbers X Y in [-1, 1] "
                               f"(e.g. goal 0.1 -0.2), got {len(args)} values")
        return GoalPoint(tuple(parse_unit(a, f"goal {'XY'[i]}") for i, a in enumerate(args)))
    if name in PACE_WORDS:
        return parse_pace(name, args)
    if name == "yaml":
        if len(args) != 1:
            raise CommandError(f"'yaml' needs one file name (quote it if it has spaces), "
                               f"got {len(args)} values")
        return YamlFile(args[0])
    raise CommandError(f"unknown command '{words[0]}': type 'help' for the list")


def parse_pace(name: str, args: list[str]) -> PaceRequest:
    if name != "step":
        if args:
            raise CommandError(f"'{name}' takes no arguments, got {len(args)}")
        return PaceRequest(name)
    if len(args) > 1:
        raise CommandError(f"'step' takes at most one number of movements, got {len(args)}")
    steps = parse_index(args[0]) if args else 1
    if not 1 <= steps <= 100_000:
        raise CommandError(f"'step' needs a number of movements from 1 to 100000, got {steps}")
    return PaceRequest("step", steps)


def parse_numbers(text: str, size: int, what: str = "the pasted action") -> np.ndarray:
    """``size`` numbers in [-1, 1] from pasted text: separated by spaces, commas or new
    lines, optionally in brackets (a Python, JSON or YAML list)."""
    cleaned = text.strip()
    if cleaned.startswith("[") and cleaned.endswith("]"):
        cleaned = cleaned[1:-1]
    words = [w for w in cleaned.replace(",", " ").split() if w]
    if not words:
        raise CommandError(f"{what} is empty: {size} numbers in [-1, 1] are needed")
    if len(words) != size:
        raise CommandError(f"{what} has {len(words)} numbers, {size} are needed")
    return np.array([parse_unit(w, f"{what}[{i}]") for i, w in enumerate(words)])


def parse_index(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise CommandError(f"'{text}' is not a whole number") from None


def parse_unit(value: Any, what: str) -> float:
    """A finite number in [-1, 1], from a typed word or a YAML value."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise CommandError(f"{what} is {value!r}, not a number")
    try:
        # Strings too: PyYAML reads 1e-3 (no dot) as a string, a person would not guess that.
        number = float(value)
    except ValueError:
        raise CommandError(f"{what} is '{value}', not a number") from None
    if math.isnan(number):
        raise CommandError(f"{what} is NaN: a number in [-1, 1] is needed")
    if math.isinf(number):
        raise CommandError(f"{what} is infinite: a number in [-1, 1] is needed")
    if not -1.0 <= number <= 1.0:
        raise CommandError(f"{what} = {number:g} is outside [-1, 1]")
    return number
