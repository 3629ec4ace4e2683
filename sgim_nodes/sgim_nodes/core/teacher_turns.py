"""Several teachers taking turns as SGIM-D's periodic teacher (issue 33's comparison).

SGIM-ACTS chooses whom to ask; SGIM-D cannot choose, so the fair comparison gives SGIM-D the
same teachers (experts.py: what each knows, how precisely it shows it) taking turns at its
boundaries: turn k, at movement k * P, is teacher ``k mod n``'s, in the order given. Each
teacher is the paper's periodic teacher (teaching.py) over its own part of the teaching set:
it judges only the goals it knows and draws among those the learner has not reached, with its
own random stream ("teacher", its name). A teacher with ``precision`` > 0 shows its action
perturbed (stream "experts", its name, as the expert's) and the outcome that action lands on
in its own copy of the world; a cast that lands on no water shows the action alone (as a
means-only demonstration).

``TeacherTurns`` quacks like Teacher for the runner and the graph's teacher node: ``due``,
``decide`` (its Turn's checks and demonstration name rows of the world's teaching set) and
``choice``. A run resumed at movement m starts at turn ceil(m / P) (``resume_at``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from .environment import Environment, is_success
from .experts import ExpertSpec
from .random_streams import member_rng
from .social_config import turn_names
from .teaching import Demonstration, Teacher, Turn, check_content


@dataclass(frozen=True)
class TurnDemonstration(Demonstration):
    """A demonstration of one turn's teacher; ``outcome`` None when its cast landed nowhere."""

    teacher: str = ""

    def shown(self, content: str) -> tuple[np.ndarray | None, np.ndarray | None]:
        if self.outcome is not None:
            return super().shown(content)
        check_content(content)
        return self.action.copy(), None


@dataclass
class _TurnTeacher:
    spec: ExpertSpec
    rows: np.ndarray
    teacher: Teacher
    rng: np.random.Generator
    world: Environment | None


class TeacherTurns:
    """The teachers of ``specs`` over one teaching set, taking turns (module docstring)."""

    def __init__(self, specs: Sequence[ExpertSpec], actions: np.ndarray, outcomes: np.ndarray,
                 seed: int, period: int, tolerance: float, choice: str,
                 make_world: Callable[[], Environment] | None = None,
                 part_of: Callable[[np.ndarray], str] | None = None) -> None:
        names = [s.name for s in specs]
        if not names or len(set(names)) != len(names):
            raise ValueError(f"teachers taking turns need distinct names, got {names}")
        actions, outcomes = np.asarray(actions, dtype=float), np.asarray(outcomes, dtype=float)
        self.turns: list[_TurnTeacher] = []
        for spec in specs:
            rows = spec.rows(outcomes, part_of)
            if len(rows) == 0:
                raise ValueError(f"teacher {spec.name!r}: no demonstration in part {spec.part!r}")
            if spec.precision > 0.0 and make_world is None:
                raise ValueError(f"teacher {spec.name!r}: an imprecise teacher needs a world "
                                 "to cast its perturbed actions in")
            teacher = Teacher(actions[rows], outcomes[rows], member_rng(seed, "teacher", spec.name),
                              period, tolerance, choice)
            world = make_world() if spec.precision > 0.0 else None
            self.turns.append(_TurnTeacher(spec, rows, teacher, member_rng(seed, "experts",
                                                                           spec.name), world))
        self.period = period
        self.choice = choice
        self.turn = 0

    @property
    def names(self) -> list[str]:
        return [t.spec.name for t in self.turns]

    def due(self, movements: int) -> bool:
        return movements % self.period == 0

    def resume_at(self, movements: int) -> None:
        """The turns before movement ``movements`` were taken (a resumed run)."""
        self.turn = math.ceil(movements / self.period)

    def teacher_at(self, turn: int) -> str:
        return self.turns[turn % len(self.turns)].spec.name

    def decide(self, reached, asked: np.ndarray | None = None) -> Turn:
        """This turn's teacher judges its goals and draws among the unreached (teaching.py);
        its checks and demonstration name rows of the world's teaching set."""
        if asked is not None:
            raise ValueError("teachers taking turns speak at their boundaries, not on request")
        me = self.turns[self.turn % len(self.turns)]
        self.turn += 1
        turn = me.teacher.decide(reached)
        checks = tuple(replace(c, index=int(me.rows[c.index])) for c in turn.checks)
        demo = turn.demonstration
        if demo is None:
            return Turn(checks, None)
        action, outcome = demo.action, demo.outcome
        if me.spec.precision > 0.0:
            action = np.clip(action + me.rng.normal(0.0, me.spec.precision, action.shape),
                             -1.0, 1.0)
            result = me.world.execute(action)
            outcome = (np.asarray(result.outcome, dtype=float).copy() if is_success(result)
                       else None)
        return Turn(checks, TurnDemonstration(int(me.rows[demo.index]), action, outcome,
                                              me.spec.name))


def turn_specs(env: str, names: str) -> tuple[ExpertSpec, ...]:
    """The world's SGIM-ACTS teachers (acts_runner.EXPERTS_BY_WORLD) named in ``names``
    (comma-separated), in that order."""
    from .acts_runner import EXPERTS_BY_WORLD

    known = {s.name: s for s in EXPERTS_BY_WORLD.get(env, ())}
    wanted = turn_names(names)
    unknown = [n for n in wanted if n not in known]
    if not wanted or unknown:
        raise ValueError(f"unknown teacher(s) {', '.join(unknown) or '(none named)'}; world "
                         f"{env!r} has {', '.join(known) or 'none'}")
    return tuple(known[n] for n in wanted)
