"""SGIM-ACTS's learning strategies: how the learner tries to learn, each with its cost.

Nguyen & Oudeyer (2012, "Active choice of teachers, learning strategies and goals for a
socially guided intrinsic motivation learner") let the learner choose, for every episode,
what to learn (a goal region) and how:

- ``autonomous``: by itself, SAGG-RIAC's goal attempt toward a goal of the region;
- ``mimicry:<teacher>``: ask that teacher for its demonstration nearest the goal, store it and
  imitate its action (as SGIM-D imitates, imitation.py);
- ``emulation:<teacher>``: ask that teacher only for the outcome of that demonstration, then
  reach it by itself with a goal attempt; the teacher's action is never shown.

Each strategy has a cost in movement-equivalents (a learner's own movement is 1) that divides
the interest of its (strategy, region) pairs, so a dear strategy must bring proportionally
more progress to be chosen as often. The defaults per kind are LearnerConfig's
``acts_cost_*`` fields (their docstrings give the reasoning: autonomous 1, emulation 5,
mimicry 10, chosen, not measured).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from .config import LearnerConfig

AUTONOMOUS = "autonomous"
MIMICRY = "mimicry"
EMULATION = "emulation"
KINDS = (AUTONOMOUS, MIMICRY, EMULATION)
SOCIAL_KINDS = (MIMICRY, EMULATION)
TEACHER_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
"""A teacher's name: a letter, then letters, digits and '_'. It appears in strategy names
after ':', and in the graph each teacher is a node in the namespace of its name, which ROS
allows no other characters in."""


def check_teacher_name(name: str) -> str:
    if not isinstance(name, str) or not TEACHER_NAME.fullmatch(name):
        raise ValueError(f"bad teacher name {name!r}: use a letter, then letters, digits or "
                         f"'_' (it names the teacher's ROS namespace)")
    return name


@dataclass(frozen=True)
class Strategy:
    """One way of learning: its kind, the teacher it asks (None when autonomous) and what
    one episode of it costs, in movement-equivalents."""

    kind: str
    teacher: str | None
    cost: float

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown strategy kind {self.kind!r}; choose one of {KINDS}")
        if (self.kind == AUTONOMOUS) != (self.teacher is None):
            raise ValueError(f"{self.kind} strategies take "
                             f"{'no teacher' if self.kind == AUTONOMOUS else 'a teacher'}")
        if self.teacher is not None:
            check_teacher_name(self.teacher)
        if not (isinstance(self.cost, int | float) and self.cost > 0.0
                and self.cost < float("inf")):
            raise ValueError(f"strategy {self.name}: cost must be a finite number > 0 (it "
                             f"divides the interest), got {self.cost!r}")

    @property
    def name(self) -> str:
        """``autonomous``, ``mimicry:<teacher>`` or ``emulation:<teacher>``."""
        return self.kind if self.teacher is None else f"{self.kind}:{self.teacher}"

    @property
    def social(self) -> bool:
        return self.teacher is not None

    @property
    def wants_action(self) -> bool:
        """Mimicry needs the teacher's action; emulation only its outcome."""
        return self.kind == MIMICRY


def default_cost(kind: str, config: LearnerConfig) -> float:
    """The configured cost of a kind of strategy (LearnerConfig.acts_cost_*)."""
    if kind not in KINDS:
        raise ValueError(f"unknown strategy kind {kind!r}; choose one of {KINDS}")
    return float(getattr(config, f"acts_cost_{kind}"))


def parse_strategy(text: str, config: LearnerConfig | None = None,
                   teachers: Iterable[str] | None = None, cost: float | None = None
                   ) -> Strategy:
    """``autonomous``, ``mimicry:NAME`` or ``emulation:NAME`` as a Strategy; ``teachers``,
    when given, are the names the learner may ask (an unknown one is refused); ``cost``
    overrides the kind's configured cost."""
    config = config or LearnerConfig()
    kind, sep, teacher = str(text).strip().partition(":")
    if kind not in KINDS:
        raise ValueError(f"bad strategy {text!r}: write autonomous, mimicry:NAME or "
                         f"emulation:NAME")
    if kind == AUTONOMOUS:
        if sep:
            raise ValueError(f"bad strategy {text!r}: autonomous asks no teacher")
        name = None
    else:
        if not teacher:
            raise ValueError(f"bad strategy {text!r}: {kind} needs a teacher, {kind}:NAME")
        name = check_teacher_name(teacher)
        if teachers is not None:
            known = tuple(teachers)
            if name not in known:
                raise ValueError(f"strategy {text!r} asks unknown teacher {name!r}; known "
                                 f"teachers: {', '.join(known) or 'none'}")
    return Strategy(kind, name, default_cost(kind, config) if cost is None else cost)


def parse_strategies(texts: Sequence[str], config: LearnerConfig | None = None,
                     teachers: Iterable[str] | None = None) -> tuple[Strategy, ...]:
    """Several strategy names, in order: at least one, none twice."""
    known = None if teachers is None else tuple(teachers)
    parsed = tuple(parse_strategy(t, config, known) for t in texts)
    if not parsed:
        raise ValueError("SGIM-ACTS needs at least one strategy")
    names = [s.name for s in parsed]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"strategy named twice: {', '.join(twice)}")
    return parsed


def all_strategies(teachers: Sequence[str], config: LearnerConfig | None = None
                   ) -> tuple[Strategy, ...]:
    """Autonomous, then mimicry and emulation of each teacher, in the teachers' order."""
    names = [AUTONOMOUS]
    for teacher in teachers:
        names += [f"{MIMICRY}:{teacher}", f"{EMULATION}:{teacher}"]
    return parse_strategies(names, config, teachers)
