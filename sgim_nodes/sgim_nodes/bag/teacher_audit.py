"""Redo the automatic teacher's turns from a bag's TeacherCheck records alone (issue 31).

With the `ability` rule the teacher judges each teaching goal by casting the learner's inverse
model in a world of its own, and nothing of those casts reached the bag before: nobody could
tell why a turn was silent or why an entry was shown again. Now each turn leaves one
TeacherCheck per teaching goal (teacher_checks), and this module redoes the turn from them: the
verdicts from distance and tolerance, the entries the teacher could draw among
(core/teaching.py, eligible), and the draw itself, with the teacher's random stream from the
run's seed (RunStatus.seed). The draw replays only a run recorded in one piece (a resumed
teacher starts its stream afresh); everything else holds for any bag. When teachers take the
turns (core/teacher_turns.py), a turn judges one teacher's rows of the set only, and the draw
is that teacher's stream: give their names, in turn order. Nothing here imports rclpy.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from sgim_nodes.bag.records import TeacherCheckRecord
from sgim_nodes.core.random_streams import component_rng, member_rng
from sgim_nodes.core.teaching import eligible


@dataclass(frozen=True)
class AuditedTurn:
    """One teacher's turn as its checks say it: which entries it could show, which one its
    stream draws (-1: silent; None: no seed given) and which its checks mark shown."""

    movement_index: int
    help_request: int  # the HelpRequest.index it answers; 0 at a periodic turn
    checks: tuple[TeacherCheckRecord, ...]  # in teaching-set order
    eligible: np.ndarray  # teaching-set rows it could draw among; empty: silent
    drawn: int | None  # what the teacher's stream draws among them (-1 when silent)
    marked: tuple[int, ...]  # the rows whose check says `chosen`: one, or none when silent

    @property
    def verdicts_hold(self) -> bool:
        """Every check's verdict is the one its distance and tolerance give."""
        return all(c.reached == (c.distance <= c.tolerance) for c in self.checks)


class IncompleteTurn(ValueError):
    """A turn's checks are not one per entry it judges (records lost or forged)."""


def turns(checks: Iterable[TeacherCheckRecord]) -> list[tuple[TeacherCheckRecord, ...]]:
    """The checks grouped by turn, in recording order, each in teaching-set order;
    IncompleteTurn when a turn lacks an entry, or mixes rules or tolerances. A turn taken
    again (a run resumed where a demonstration was given and not taken) is a turn of its own:
    its entries come again after the whole first set."""
    grouped: list[tuple[tuple[int, int], list[TeacherCheckRecord]]] = []
    open_: dict[tuple[int, int], list[TeacherCheckRecord]] = {}
    for check in checks:
        group = open_.get(check.turn)
        if group is None or (len(group) >= group[0].entries and check.teaching_set_index in
                             {c.teaching_set_index for c in group}):
            group = open_[check.turn] = []
            grouped.append((check.turn, group))
        group.append(check)
    out = []
    for (movement, ask), group in grouped:
        group.sort(key=lambda c: c.teaching_set_index)
        first = group[0]
        rows = [c.teaching_set_index for c in group]
        if (len(rows) != first.entries or len(set(rows)) != len(rows)
                or len({(c.entries, c.rule, c.choice, c.tolerance) for c in group}) != 1):
            raise IncompleteTurn(f"the turn at movement {movement} (help request {ask}) has "
                                 f"checks of entries {[c.teaching_set_index for c in group]}, "
                                 f"not one of each of its {first.entries}")
        out.append(tuple(group))
    return out


def redo(checks: Iterable[TeacherCheckRecord], seed: int | None = None,
         teacher_turns: Sequence[str] = ()) -> list[AuditedTurn]:
    """Every turn redone from its checks; with the run's `seed`, the teacher's draws too
    (those of the teachers of `teacher_turns`, in turn, when they took the turns)."""
    if seed is None:
        streams = None
    elif teacher_turns:
        streams = [member_rng(seed, "teacher", name) for name in teacher_turns]
    else:
        streams = [component_rng(seed, "teacher")]
    audited = []
    for k, group in enumerate(turns(checks)):
        first = group[0]
        asked = first.asked_goal if len(first.asked_goal) else None
        rows = np.array([c.teaching_set_index for c in group], dtype=int)
        places = eligible(np.array([c.distance for c in group]), first.tolerance,
                          first.choice, np.array([c.goal for c in group]), asked)
        pool = rows[places]
        rng = None if streams is None else streams[k % len(streams)]
        drawn = (None if rng is None else -1 if len(places) == 0
                 else int(rows[int(rng.choice(places))]))
        marked = tuple(c.teaching_set_index for c in group if c.chosen)
        audited.append(AuditedTurn(first.movement_index, first.help_request, group, pool,
                                   drawn, marked))
    return audited
