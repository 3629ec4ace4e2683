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

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sgim_nodes.bag.reader import load_run, superseded_removed
from sgim_nodes.bag.rebuild import RebuiltState, rebuild_from_records
from sgim_nodes.bag.records import RunRecords
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.teaching import OWN_PROCESSES

FIRST_SEGMENT = "bag"
_RESUMED = re.compile(r"^bag\.resume(\d+)$")


def segments(run_dir: str | Path) -> list[Path]:
    """The run's recordings in the order they were made."""
    run_dir = Path(run_dir)
    later = sorted(((int(m.group(1)), p) for p in run_dir.iterdir()
                    if (m := _RESUMED.match(p.name))), key=lambda t: t[0])
    first = run_dir / FIRST_SEGMENT
    return ([first] if first.exists() else []) + [p for _, p in later]


def next_segment(run_dir: str | Path) -> Path:
    run_dir = Path(run_dir)
    if not (run_dir / FIRST_SEGMENT).exists():
        return run_dir / FIRST_SEGMENT
    return run_dir / f"bag.resume{len(segments(run_dir))}"


def load_run_folder(run_dir: str | Path, limit: int = 0) -> RunRecords:
    """Every record of a run across its recordings (the first `limit` ones if > 0: a resumed
    graph reads only those made before its own), as one RunRecords."""
    parts = segments(run_dir)
    if limit > 0:
        parts = parts[:limit]
    if not parts:
        raise FileNotFoundError(f"{run_dir}: no recording ('{FIRST_SEGMENT}/') in this folder")
    merged = RunRecords()
    for part in parts:
        run = load_run(part)
        for name in vars(merged):
            getattr(merged, name).extend(getattr(run, name))
    merged.movements = superseded_removed(merged.movements, str(run_dir))
    return merged


def records_until(records: RunRecords, count: int) -> RunRecords:
    """The records of a run as they stood right after movement `count` (a demonstration given
    at `count` came after it)."""
    return RunRecords(
        movements=[m for m in records.movements if m.index <= count],
        goals=[g for g in records.goals if g.movement_index <= count],
        competences=[c for c in records.competences if c.movement_index <= count],
        demonstrations=[d for d in records.demonstrations if d.movement_index < count],
        evaluations=[e for e in records.evaluations if e.movement_index <= count],
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
    evaluated: set[int] = field(default_factory=set)

    @property
    def latest_demonstration(self):
        demos = [d for d in self.records.demonstrations if len(d.action)]
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
        demonstrations_given=sum(1 for d in records.demonstrations if len(d.action)),
        evaluated={e.movement_index for e in records.evaluations},
    )
