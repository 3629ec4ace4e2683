"""One frozen configuration of a run's social settings: when the teacher speaks, what it
counts as reached, which goal it shows and what a demonstration shows, beside LearnerConfig.

Each setting is declared here once, with its default, its bounds (a field's metadata) and its
source (its docstring). The single-process runner takes a SocialConfig; the graph's teacher
and arbiter declare their ROS parameters from it under the same names (nodes/ros_glue.py);
the launcher's defaults, learner.yaml and the reference page read it too.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any

from .config import AT_LEAST_ONE, NON_NEGATIVE, Range
from .help_request import DEFAULT_TIMING, ON_REQUEST, TIMINGS
from .teaching import (
    DEFAULT_DEMONSTRATION_CONTENT,
    DEFAULT_REACHED_RULE,
    DEFAULT_TEACHER_CHOICE,
    DEFAULT_TOLERANCE_NOISE,
    DEMONSTRATION_CONTENTS,
    PAPER_PERIOD,
    REACHED_RULES,
    TEACHER_CHOICES,
)


@dataclass(frozen=True)
class SocialConfig:
    """The social settings of a run (sources in each field's docstring). A field's metadata
    holds its meaning in one line (``help``: the ROS parameter's and the YAML's) and its
    ``range`` (config.Range, as LearnerConfig's fields)."""

    demonstration_period: int = field(default=PAPER_PERIOD, metadata={
        "range": AT_LEAST_ONE,
        "help": "the paper's P: the automatic teacher's turn every P movements "
        "(on request: one ask earned per P)"})
    """The automatic teacher's period P: a turn at movements 0, P, 2P, ... (the paper: 150).
    On request, the learner earns one ask per P movements."""

    timing: str = field(default=DEFAULT_TIMING, metadata={
        "range": Range(choices=TIMINGS),
        "help": "when the automatic teacher speaks: period (every P "
        "movements, the paper) or on-request (when the learner asks; the arbiter and the "
        "teacher read it)"})
    """When the automatic teacher speaks: 'period' (every P movements, the paper) or
    'on-request' (when the learner asks, its progress stalled; core/help_request.py)."""

    reached_rule: str = field(default=DEFAULT_REACHED_RULE, metadata={
        "range": Range(choices=REACHED_RULES),
        "help": "reached = the learner's inverse model cast for the "
        "goal lands within the tolerance (own-movements: one of its own movements did)"})
    """When a teaching goal counts as reached: 'ability' (the learner's inverse model cast for
    it lands within the tolerance) or 'own-movements' (one of its own movements landed there);
    core/teaching.py."""

    teacher_choice: str = field(default=DEFAULT_TEACHER_CHOICE, metadata={
        "range": Range(choices=TEACHER_CHOICES),
        "help": "which unreached goal: random-unreached (the "
        "paper), farthest-unreached or nearest-unreached"})
    """Which unreached teaching goal the teacher shows: 'random-unreached' (the paper),
    'farthest-unreached' or 'nearest-unreached' (from what the learner can do)."""

    demonstration_content: str = field(default=DEFAULT_DEMONSTRATION_CONTENT, metadata={
        "range": Range(choices=DEMONSTRATION_CONTENTS),
        "help": "what it shows: means-and-goal (the paper), "
        "goal-only (the outcome: emulation) or means-only (the action)"})
    """What a demonstration shows: 'means-and-goal' (the action and its outcome, the paper),
    'goal-only' (the outcome: emulation) or 'means-only' (the action); core/teaching.py."""

    tolerance_noise: float = field(default=DEFAULT_TOLERANCE_NOISE, metadata={
        "range": NON_NEGATIVE,
        "help": "a teaching goal counts as reached within this many units of "
        "the world's outcome noise"})
    """A teaching goal counts as reached within this many units of the world's outcome
    noise."""

    teacher_turns: tuple[Any, ...] = ()
    """Several teachers take the teacher's turns, in this order (core/teacher_turns.py);
    empty: one teacher who knows the whole teaching set."""

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            problem = f.metadata["range"].problem(value) if "range" in f.metadata else ""
            if problem:
                raise ValueError(f"{f.name} {problem}, got {value!r}")
        if self.teacher_turns and self.timing == ON_REQUEST:
            raise ValueError("teacher_turns speak at their boundaries: timing on-request has "
                             "one teacher")


def turn_names(names: str) -> tuple[str, ...]:
    """The teachers' names of a comma-separated ``names`` (as --teacher-turns and the
    teacher node's parameter give them), in their order: SocialConfig.teacher_turns."""
    return tuple(n.strip() for n in names.split(",") if n.strip())


SOCIAL_DEFAULTS = SocialConfig()
"""Every setting at its default: what other modules read a default from."""


def declared(name: str) -> dict[str, Any]:
    """A setting's declaration: its default and its metadata (help, range)."""
    f = next(f for f in fields(SocialConfig) if f.name == name)
    return {"default": getattr(SOCIAL_DEFAULTS, name), **f.metadata}
