"""Resume an interrupted run from its recording.

A run folder holds its first recording in `bag/` and one more per resumption
(`bag.resume1/`, `bag.resume2/`, ...). Together they are the run's whole history, so every node
that holds learning state rebuilds it from them at start-up (parameter `resume_from`): the
memory and the region tree (rebuild.py), the movement count, the goals, demonstrations and
evaluations already done. The resumed graph then carries on to the run's movement budget.

What cannot be restored: the random streams and the simulator's noise stream start again
from the seed, so a resumed run reaches the same final count but not the very movements an
uninterrupted run would have made.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from sgim_nodes.bag.records import DemonstrationRecord, MovementRecord, RunRecords
from sgim_nodes.bag.run_folder import (  # noqa: F401 - the launcher's names for them
    FIRST_SEGMENT,
    load_run_folder,
    next_segment,
    segments,
)
from sgim_nodes.core.competence import NearestOutcome
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.environment import PROCESS_CODES
from sgim_nodes.core.teaching import OWN_PROCESSES

IMITATION_CODE = PROCESS_CODES["imitation"]

if TYPE_CHECKING:
    from sgim_nodes.bag.rebuild import RebuiltState


def records_until(records: RunRecords, count: int) -> RunRecords:
    """The records of a run as they stood right after movement `count` (a demonstration given
    at `count` came after it)."""
    return RunRecords(
        movements=[m for m in records.movements if m.index <= count],
        goals=[g for g in records.goals if g.movement_index <= count],
        competences=[c for c in records.competences if c.movement_index <= count],
        demonstrations=[d for d in records.demonstrations if d.movement_index < count],
        demonstrations_taken=[d for d in records.demonstrations_taken
                              if d.movement_index < count],
        help_requests=[h for h in records.help_requests if h.movement_index < count],
        evaluations=[e for e in records.evaluations if e.movement_index <= count],
        topics=set(records.topics),
    )


@dataclass
class ResumePoint:
    """Where a run stopped, and the state its nodes rebuild."""

    state: RebuiltState
    records: RunRecords
    count: int  # learner movements done
    goal_index: int  # the last goal's index
    demonstration_turns: set[int] = field(default_factory=set)  # teacher turns already taken
    demonstrations_given: int = 0  # non-empty demonstrations
    help_requests_answered: set[int] = field(default_factory=set)  # HelpRequest.index answered
    evaluated: set[int] = field(default_factory=set)

    @property
    def latest_demonstration(self):
        """The last demonstration the learner took (demo-only varies it)."""
        demos = self.records.learner_demonstrations
        return demos[-1] if demos else None

    @property
    def reached_outcomes(self) -> np.ndarray:
        return self.state.memory.outcomes

    @property
    def own_outcomes(self) -> np.ndarray:
        """Outcomes of the learner's own movements (core/teaching.py OWN_PROCESSES)."""
        labels = np.asarray(self.state.memory.labels)
        return self.state.memory.outcomes[np.isin(labels, OWN_PROCESSES)]


def resume_point(run_dir: str | Path, config: LearnerConfig | None = None,
                 limit: int = 0) -> ResumePoint:
    # Imported here: the rebuild brings the learner's whole core (scipy's trees included),
    # which a node starting a fresh run never needs; six nodes import this module.
    from sgim_nodes.bag.rebuild import rebuild_from_records

    records = load_run_folder(run_dir, limit)
    state = rebuild_from_records(records, config)
    count = state.n_movements
    return ResumePoint(
        state=state, records=records, count=count,
        goal_index=max((g.index for g in records.goals), default=0),
        demonstration_turns=finished_turns(records, count),
        demonstrations_given=sum(1 for d in records.demonstrations if d.shown),
        help_requests_answered=finished_asks(records, count),
        evaluated={e.movement_index for e in records.evaluations},
    )


def finished_turns(records: RunRecords, count: int) -> set[int]:
    """The teacher's turns (movement counts) the run is done with: those the learner took a
    demonstration at, and those it went on from. A word given at the count where the run
    stopped, and not taken, is a turn still to come: the arbiter waits there, and the teacher
    speaks again (issue 31: counting the word given lost the turn)."""
    taken = {d.movement_index for d in records.learner_demonstrations if not d.help_request}
    passed = {d.movement_index for d in records.demonstrations
              if not d.help_request and d.movement_index < count}
    return taken | passed


def finished_asks(records: RunRecords, count: int) -> set[int]:
    """The help requests answered for good: the answer taken, or the run went on from it."""
    taken = {d.help_request for d in records.learner_demonstrations if d.help_request}
    passed = {d.help_request for d in records.demonstrations
              if d.help_request and d.movement_index < count}
    return taken | passed


@dataclass(frozen=True)
class CutImitation:
    """The imitation of the last demonstration taken, cut by the run's end: the movements it
    made, and how many it owed (``imitation_count``, or fewer at the budget's end)."""

    demonstration: DemonstrationRecord
    made: list[MovementRecord]
    owed: int
    competence_recorded: bool

    @property
    def remaining(self) -> int:
        return max(0, self.owed - len(self.made))

    @property
    def measured(self) -> bool:
        """Its competence is recorded when the teacher showed where the action lands."""
        return bool(len(self.demonstration.outcome))

    def best_outcome(self) -> np.ndarray | None:
        """The made imitation's outcome nearest the demonstrated one (the first of equals)."""
        nearest = NearestOutcome(np.asarray(self.demonstration.outcome, float))
        for m in self.made:
            nearest.observe(m)
        return nearest.outcome

    def describe(self) -> str:
        d = self.demonstration
        done = (f"its {self.remaining} other imitation(s) are made" if self.remaining
                else "its imitations were all made")
        measure = " and its competence recorded" if self.measured else ""
        return (f"the imitation of demonstration {d.index} (taken at movement "
                f"{d.movement_index}) was cut after {len(self.made)} of {self.owed} "
                f"movements: {done}{measure} before the learner goes on")


def cut_imitation(records: RunRecords, count: int, imitation_count: int,
                  budget: int) -> CutImitation | None:
    """The imitation the run stopped in the middle of, or None: the last demonstration taken
    shows an action, only its imitation's movements come after it, and fewer than it owed were
    made (or all were, but the competence of one that shows its outcome is missing)."""
    shown = [d for d in records.learner_demonstrations if len(d.action)]
    if not shown:
        return None
    demo = shown[-1]
    later = sorted((m for m in records.movements if m.index > demo.movement_index
                    and m.process != PROCESS_CODES["evaluation"]), key=lambda m: m.index)
    if any(m.process != IMITATION_CODE for m in later) or any(
            d.movement_index > demo.movement_index for d in records.learner_demonstrations):
        return None  # the run went on after it: its imitation ended
    made = list({m.index: m for m in later}.values())  # a re-execution counts once
    owed = min(imitation_count, budget - demo.movement_index)
    recorded = any(c.from_demonstration and c.movement_index > demo.movement_index
                   for c in records.competences)
    cut = CutImitation(demo, made, owed, recorded)
    if cut.remaining or (cut.measured and not recorded and made):
        return cut
    return None


def imitation_start_distance(records: RunRecords, demo: DemonstrationRecord,
                             config: LearnerConfig | None = None) -> float:
    """Memory's distance to the demonstrated outcome before the demonstration was stored, as
    the explorer measured it when it took it (the competence of its imitation is measured
    against it)."""
    from sgim_nodes.bag.rebuild import rebuild_from_records

    before = rebuild_from_records(records_until(records, demo.movement_index), config)
    return before.memory.closest_distance(np.asarray(demo.outcome, float))


def what_is_redone(records: RunRecords, count: int, imitation_count: int = 0,
                   budget: int = 0) -> list[str]:
    """The resume report, turn by turn: what the run stopped in the middle of, and what the
    resumed run does about it (``imitation_count`` and ``budget``: the run's, to name a cut
    imitation)."""
    lines = []
    cut = cut_imitation(records, count, imitation_count, budget) if imitation_count else None
    if cut is not None:
        lines.append(cut.describe())
    turns, asks = finished_turns(records, count), finished_asks(records, count)
    for d in records.demonstrations:
        if d.help_request and d.help_request not in asks:
            lines.append(f"help request {d.help_request} at movement {d.movement_index} was "
                         "answered but the answer was not taken: the learner asks again")
        elif not d.help_request and d.movement_index not in turns:
            what = (f"demonstration {d.index} (teaching entry {d.teaching_set_index}) was "
                    "given" if d.shown else "the teacher said it had nothing to show")
            lines.append(f"the teacher's turn at movement {d.movement_index}: {what}, but the "
                         "learner did not take it: the turn is taken again")
    answered = {c.goal_index for c in records.competences if c.goal_index > 0}
    last = max((g.index for g in records.goals), default=0)
    by_goal: dict[int, list[int]] = {}
    for m in records.movements:
        by_goal.setdefault(m.goal_index, []).append(m.index)
    for goal in records.goals:
        if goal.index in answered:
            continue
        made = by_goal.get(goal.index, [])
        if made:
            lines.append(f"goal {goal.index} was interrupted after its movements "
                         f"{made[0]}-{made[-1]}: they stay in memory, but its competence was "
                         "never recorded, so the interest tree does not hold that attempt "
                         "(dropped)")
        elif goal.index == last:
            lines.append(f"goal {goal.index} was drawn but the run stopped before its first "
                         "movement: dropped")
    return lines
