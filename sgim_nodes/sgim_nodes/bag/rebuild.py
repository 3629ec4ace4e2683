"""Rebuild the learner's state from a run's bag, to analyse the run or resume it.

The bag is the run's only complete history, so the learner's memory and interest tree must be
derivable from it alone, with the real core classes (not a re-implementation that could
drift). Every record is first validated by the reader (bag/validation.py, the live nodes'
checks): a quarantined record is never folded, and the summary says how many there were.
  memory  every successful learner movement, plus every demonstration the learner took (the
          arbiter's `demonstrations_taken`; in a bag recorded before it existed, every
          non-empty demonstration) that showed both its action and its outcome (a goal-only
          or means-only one gives memory nothing: the learner stores no pair from it), in
          movement-count order; a demonstration taken at count k goes after movement k (it
          was registered before movement k+1), whatever the order the topics arrived in;
  tree    the recorded competences folded into a RegionTree in movement-count order (ties
          keep the recording order), with the LearnerConfig's region parameters.
The last recorded region map, when there is one, is compared with the rebuilt leaves.

CLI: python -m sgim_nodes.bag.rebuild BAG_OR_RUN_FOLDER [--set name=value ...]   (a summary)
A run folder (run_experiment.sh's, with bag/ and maybe bag.resume1/, ...) is read whole.
"""

from __future__ import annotations

import ast
import sys
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sgim_nodes.bag.reader import NotABagError
from sgim_nodes.bag.records import (
    DemonstrationRecord,
    EvaluationRecord,
    MovementRecord,
    RegionMapRecord,
    RunRecords,
    RunStatusRecord,
)
from sgim_nodes.bag.run_folder import load_records
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.environment import PROCESS_CODES, PROCESS_LABELS, Status
from sgim_nodes.core.learners import DEMONSTRATION, region_tree_for
from sgim_nodes.core.memory import Memory
from sgim_nodes.core.region_tree import RegionTree
from sgim_nodes.core.scale import WorldScale, unit_box
from sgim_ros.command_line import BriefParser

PROCESS_EVALUATION = PROCESS_CODES["evaluation"]  # never stored in memory
STATUS_OK = Status.OK
DEFAULT_DIMS = (24, 2)  # the fishing world's action and outcome sizes, for an empty bag
STATE_NAMES = {0: "running", 1: "finished", 2: "aborted"}


@dataclass
class RebuiltState:
    memory: Memory
    tree: RegionTree
    n_movements: int  # the learner's movement count: the highest Movement.index recorded
    n_recorded: int  # learner movements present in the bag
    missing: list[int] = field(default_factory=list)  # indices 1..n_movements not recorded
    duplicates: int = 0  # records superseded by a re-execution of the same index
    quarantined: list = field(default_factory=list)  # validation.Quarantined, not folded
    n_memory_movements: int = 0
    n_demonstrations: int = 0
    n_competences: int = 0
    last_evaluation: EvaluationRecord | None = None
    last_status: RunStatusRecord | None = None
    last_region_map: RegionMapRecord | None = None

    def region_map_matches(self) -> bool | None:
        """Whether the rebuilt leaves are the last recorded map's leaves (None: no map)."""
        if self.last_region_map is None:
            return None
        ours = sorted((tuple(r.low), tuple(r.high)) for r in self.tree.leaves)
        theirs = sorted((tuple(r.lower), tuple(r.upper)) for r in self.last_region_map.leaves)
        return len(ours) == len(theirs) and all(
            np.allclose(a[0], b[0]) and np.allclose(a[1], b[1])
            for a, b in zip(ours, theirs, strict=True))


def _dims(run: RunRecords) -> tuple[int, int]:
    action = next((len(r.action) for r in [*run.movements, *run.learner_demonstrations]
                   if len(r.action)), DEFAULT_DIMS[0])
    outcome = next((len(r.outcome) for r in [*run.movements, *run.learner_demonstrations]
                    if len(r.outcome)), DEFAULT_DIMS[1])
    return action, outcome


FISHING_NOISE = 0.07  # sim_bridge.scaling.OUTCOME_NOISE, without importing the world


def rebuild_from_records(run: RunRecords, config: LearnerConfig | None = None,
                         scale: WorldScale | None = None) -> RebuiltState:
    """Fold the (validated) records of a run into a fresh Memory and RegionTree (``scale``:
    the world's outcome box and noise; default the fishing world's, [-1, 1]^m)."""
    c = config or LearnerConfig()
    action_dim, outcome_dim = _dims(run)
    memory = Memory(action_dim, outcome_dim, c.memory_rebuild_fraction, c.memory_min_tail,
                    c.memory_max_tail)
    tree: RegionTree = region_tree_for(c, scale or unit_box(outcome_dim, FISHING_NOISE))
    movements = [m for m in run.movements if m.process != PROCESS_EVALUATION]
    entries: list[tuple[int, int, MovementRecord | DemonstrationRecord]] = [
        (m.index, 0, m) for m in movements] + [(d.movement_index, 1, d)
                                               for d in run.learner_demonstrations]
    entries.sort(key=lambda e: (e[0], e[1]))  # stable: ties keep the recording order
    n_mem = n_demos = 0
    for _, is_demo, record in entries:
        if is_demo:  # an empty one means "nothing left to show": not a demonstration
            if len(record.action) == action_dim and len(record.outcome) == outcome_dim:
                memory.add(record.action, record.outcome, DEMONSTRATION)
                n_demos += 1
        elif record.status == STATUS_OK and len(record.outcome) == outcome_dim:
            memory.add(record.action, record.outcome, PROCESS_LABELS.get(record.process, ""))
            n_mem += 1
    for comp in sorted(run.competences, key=lambda r: r.movement_index):
        tree.add(comp.goal, comp.competence)
    indices = {m.index for m in movements if m.index}
    n_movements = max(indices, default=0)
    return RebuiltState(
        memory=memory,
        tree=tree,
        n_movements=n_movements,
        n_recorded=len(movements),
        missing=sorted(set(range(1, n_movements + 1)) - indices),
        duplicates=len(run.superseded),
        quarantined=list(run.quarantined),
        n_memory_movements=n_mem,
        n_demonstrations=n_demos,
        n_competences=len(run.competences),
        last_evaluation=run.evaluations[-1] if run.evaluations else None,
        last_status=run.run_status[-1] if run.run_status else None,
        last_region_map=run.region_map[-1] if run.region_map else None,
    )


def rebuild(path: str | Path, config: LearnerConfig | None = None) -> RebuiltState:
    """Rebuild from a bag directory, a storage file or a run folder (every segment); damaged
    parts are skipped with a BagReadWarning; NotABagError says what the path is otherwise."""
    return rebuild_from_records(load_records(path)[0], config)


def summary(state: RebuiltState) -> str:
    missing = f", {len(state.missing)} missing" if state.missing else ""
    dups = (f", {state.duplicates} superseded by their re-execution" if state.duplicates
            else "")
    lines = [
        f"movements: {state.n_movements} (learner count), {state.n_recorded} recorded"
        f"{missing}{dups}",
        f"memory: {len(state.memory)} pairs ({state.n_memory_movements} successful movements "
        f"+ {state.n_demonstrations} demonstrations)",
        f"region tree: {state.n_competences} competences folded, {len(state.tree.leaves)} leaf "
        f"regions",
    ]
    if state.last_region_map is not None:
        verdict = "matches" if state.region_map_matches() else "DIFFERS FROM"
        lines.append(f"last region map (movement {state.last_region_map.movement_index}, "
                     f"{len(state.last_region_map.leaves)} leaves): rebuilt tree {verdict} it")
    e = state.last_evaluation
    lines.append("last evaluation: none" if e is None else
                 f"last evaluation: at movement {e.movement_index}, mean distance "
                 f"{e.mean_distance:.4f} over {len(e.distances)} goals")
    if state.quarantined:
        counts = Counter(f"{q.topic} ({q.problem.kind})" for q in state.quarantined)
        lines.append(f"quarantined: {len(state.quarantined)} records left out (still in the "
                     "bag): " + ", ".join(f"{n} {what}" for what, n in counts.most_common()))
    s = state.last_status
    if s is not None:
        lines.append(f"run status: {STATE_NAMES.get(s.state, s.state)} ({s.learner}, seed "
                     f"{s.seed}, {s.movement_index}/{s.total_movements} movements)"
                     + (f": {s.message}" if s.message else ""))
    return "\n".join(lines)


def _config(settings: list[str]) -> LearnerConfig:
    values = {}
    for item in settings:
        name, sep, text = item.partition("=")
        if not sep or name not in LearnerConfig.field_names():
            raise ValueError(f"--set {item!r}: expected NAME=VALUE with NAME one of "
                             f"{', '.join(LearnerConfig.field_names())}")
        try:
            values[name] = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            raise ValueError(f"--set {item!r}: {text!r} is not a number or literal") from None
    return LearnerConfig(**values)


def main(argv: list[str] | None = None) -> int:
    parser = BriefParser(
        prog="rebuild", description="Rebuild the learner's memory and region tree from a "
        "run's bag and print a summary.")
    parser.add_argument("bag", type=Path, help="bag directory, one .mcap / .db3 file, or a run "
                        "folder (bag/ and its bag.resumeN/ segments are read in order)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="a LearnerConfig value, e.g. --set max_goals_per_region=50")
    args = parser.parse_args(argv)
    try:
        config = _config(args.set)
    except ValueError as error:  # LearnerConfig's own checks raise ValueError too
        parser.error(str(error))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            records, read = load_records(args.bag)
            print(f"read: {', '.join(str(p) for p in read)}", file=sys.stderr)
            state = rebuild_from_records(records, config)
        except NotABagError as error:
            print(f"rebuild: {error}", file=sys.stderr)
            return 2
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    print(summary(state))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
