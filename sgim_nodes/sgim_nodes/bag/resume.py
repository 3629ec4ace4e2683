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

import numpy as np

from sgim_nodes.bag.rebuild import RebuiltState, rebuild_from_records
from sgim_nodes.bag.records import RunRecords
from sgim_nodes.bag.run_folder import (  # noqa: F401 - the launcher's names for them
    FIRST_SEGMENT,
    load_run_folder,
    next_segment,
    segments,
)
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.teaching import OWN_PROCESSES


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
    records = load_run_folder(run_dir, limit)
    state = rebuild_from_records(records, config)
    return ResumePoint(
        state=state, records=records, count=state.n_movements,
        goal_index=max((g.index for g in records.goals), default=0),
        demonstration_turns={d.movement_index for d in records.demonstrations},
        demonstrations_given=sum(1 for d in records.demonstrations if d.shown),
        help_requests_answered={d.help_request for d in records.demonstrations
                                if d.help_request},
        evaluated={e.movement_index for e in records.evaluations},
    )
