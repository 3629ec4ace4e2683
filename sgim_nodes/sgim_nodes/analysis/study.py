"""Find the runs of a study folder and load each bag once into compact numpy arrays.

Why arrays and a cache: a 5000-movement bag holds tens of thousands of messages and takes
seconds to deserialise; the statistics and figures only need a few columns of it. Each run's
columns are saved next to its bag (`analysis_cache.npz`, keyed by the bag files' sizes and
mtimes), so changing a figure option re-reads nothing. A damaged bag must not stop a study:
whatever is readable is used, the damage is reported naming the file, and a run with nothing
readable is skipped.

Layout: `<study>/<learner>-seed<N>/bag/` (and `bag.resume1/`, ... when the run was resumed:
every segment is read, in order) plus `metadata.yaml` (learner, seed, movements, outcome,
duration_s, parameters); the metadata wins over the folder name when both exist. Records are
validated as every reader validates them (bag/validation.py): quarantined ones are reported,
never counted.

Runs are pooled only with their like: runs of one learner whose teacher, budget or parameters
differ are split into groups labelled by what differs (a warning says so), and two runs of
one group with the same seed are not independent samples: `Study.repeated_seeds` lists them
so that the command refuses to pool them unless told to.
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from sgim_nodes.bag.reader import BagReadWarning, NotABagError
from sgim_nodes.bag.records import RegionMapRecord
from sgim_nodes.bag.run_folder import load_run_folder, segments
from sgim_nodes.core.environment import PROCESS_CODES, Status
from sgim_nodes.core.learner_registry import compared_names
from sgim_nodes.provenance import fingerprint

CACHE_NAME = "analysis_cache.npz"
CACHE_VERSION = 5  # 2: validated records, every segment; 3: sources, SGIM-ACTS's choices;
# 4: the goal mode of each SGIM-ACTS choice; 5: each evaluation's distances goal by goal
OUTCOME_SIZE = 2
PROCESS_IMITATION, PROCESS_DEMONSTRATION, PROCESS_EVALUATION = (
    PROCESS_CODES[label] for label in ("imitation", "demonstration", "evaluation"))
STATUS_OK = int(Status.OK)
LEARNER_ORDER = compared_names(plugins=False)  # the paper's learners first, in their order
_RUN_NAME = re.compile(r"^(?P<learner>.+)-seed(?P<seed>\d+)$")
_WANTED = ("movements", "evaluations", "region_map", "demonstrations", "demonstrations_taken",
           "run_status", "help_requests", "goals")
# Parameters that differ from run to run without changing the experiment: the fingerprint's.
PER_RUN = fingerprint.PER_RUN | fingerprint.OPERATIONAL
RUN_TIME = frozenset({"linger", "teacher_timeout", "call_timeout", "evaluation_timeout",
                      "service_timeout", "service_retries", "goal_timeout"})
"""The parameters the nodes declare changeable while they run (``read_only=False``): how long
a node waits and how long the web page stays. None changes a movement (a wait too short ends
the run, it does not alter it), so the fingerprint leaves them out too
(fingerprint.graph_parameters); tests/analysis/test_pooling_settings.py checks the list
against the nodes' declarations."""
SILENT = frozenset({"chunk_seconds", "chunk_messages", "finish_grace", "stop_on_finish",
                    "full_every", "rate"})
"""The parameters of the nodes that only record or draw (fingerprint.SILENT_NODES) that no
other node declares: how the bag is written, how often the markers are drawn."""
NOT_THE_RUN = PER_RUN | RUN_TIME | SILENT
"""What two runs may differ in and still be pooled: nothing here changes what the learner
does."""

Warn = Callable[[str], None]


class AnalysisWarning(UserWarning):
    """A run of the study is damaged or incomplete; the analysis went on without (part of) it."""


def _default_warn(message: str) -> None:
    warnings.warn(AnalysisWarning(message), stacklevel=3)


@dataclass
class RunData:
    """The columns of one run the analysis needs; outcome rows are NaN when the cast failed."""

    name: str
    path: Path
    learner: str
    seed: int
    metadata: dict
    movement_index: np.ndarray  # (N,) learner movement count, 1-based
    process: np.ndarray  # (N,) Movement.PROCESS_*
    status: np.ndarray  # (N,) Movement.STATUS_*
    outcome: np.ndarray  # (N, 2)
    eval_index: np.ndarray  # (E,) movement count of each evaluation, increasing
    eval_mean: np.ndarray  # (E,) mean distance to the benchmark goals
    demo_index: np.ndarray  # (D,)
    demo_outcome: np.ndarray  # (D, 2)
    map_index: np.ndarray  # (M,) movement count of each region map, increasing
    map_offsets: np.ndarray  # (M + 1,) leaves of map k are rows offsets[k]:offsets[k+1]
    leaf_lower: np.ndarray  # (R, 2)
    leaf_upper: np.ndarray  # (R, 2)
    leaf_interest: np.ndarray  # (R,)
    demo_source: np.ndarray = field(default_factory=lambda: np.zeros(0, str))  # (D,)
    # each evaluation goal by goal (a row of NaN when its goals are not the last one's), and
    # the goals of the last evaluation, in its order
    eval_distances: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (E, G)
    eval_goals: np.ndarray = field(default_factory=lambda: np.zeros((0, OUTCOME_SIZE)))  # (G, 2)
    # SGIM-ACTS (issue 33; empty for the others and for bags without these records): its
    # requests (HelpRequest: count when asked, teacher, what it asked to be shown, goal) and
    # each episode's strategy (the Goals that name one, with the count when it was chosen).
    ask_index: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))  # (Q,)
    ask_teacher: np.ndarray = field(default_factory=lambda: np.zeros(0, str))  # (Q,)
    ask_content: np.ndarray = field(default_factory=lambda: np.zeros(0, str))  # (Q,)
    ask_goal: np.ndarray = field(default_factory=lambda: np.zeros((0, OUTCOME_SIZE)))
    choice_index: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))  # (C,)
    choice_strategy: np.ndarray = field(default_factory=lambda: np.zeros(0, str))  # (C,)
    choice_mode: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint8))  # (C,)
    budget: int = -1  # RunStatus.total_movements, -1 when never published
    final_state: int = -1  # the last RunStatus.state, -1 when none
    warnings: list[str] = field(default_factory=list)
    group: str = ""  # the label it is pooled under (its learner, unless like runs differ)

    def __post_init__(self) -> None:
        self.group = self.group or self.learner

    @property
    def condition(self) -> dict:
        """What must be equal for two runs to be pooled: learner, teacher, budget and every
        parameter that can change a movement (not the seed, paths, waits or the recording:
        NOT_THE_RUN)."""
        params = self.metadata.get("parameters")
        params = params if isinstance(params, dict) else {}
        found = {k: v for k, v in params.items() if k not in NOT_THE_RUN}
        found.update(learner=self.learner, movements=self.total_movements)
        if "teacher" in self.metadata:
            found["teacher"] = self.metadata["teacher"]
        return found

    @property
    def total_movements(self) -> int:
        """The run's movement budget: metadata first, then the bag, then what was done."""
        for value in (self.metadata.get("movements"), self.budget):
            if isinstance(value, int) and value > 0:
                return value
        return int(self.movement_index.max()) if len(self.movement_index) else 0

    @property
    def movements_done(self) -> int:
        return int(self.movement_index.max()) if len(self.movement_index) else 0

    @property
    def duration_s(self) -> float | None:
        value = self.metadata.get("duration_s")
        return float(value) if isinstance(value, int | float) else None

    @property
    def finished(self) -> bool:
        """Said finished (by its metadata or its last status) and recorded to its budget: a
        bag that ends early is not a finished run, whatever its metadata claims."""
        said = self.metadata.get("outcome") == "finished" or self.final_state == 1
        return said and self.movements_done >= self.total_movements

    def region_map_at(self, movement: int) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        """(map movement count, lower, upper, interest) of the leaves of the map closest to
        `movement`; the later map wins a tie, since it holds the same goals and more."""
        if not len(self.map_index):
            empty = np.zeros((0, OUTCOME_SIZE))
            return -1, empty, empty, np.zeros(0)
        k = int(np.argmin(np.abs(self.map_index[::-1] - movement)))
        k = len(self.map_index) - 1 - k
        rows = slice(int(self.map_offsets[k]), int(self.map_offsets[k + 1]))
        return (int(self.map_index[k]), self.leaf_lower[rows], self.leaf_upper[rows],
                self.leaf_interest[rows])


@dataclass
class Study:
    path: Path
    runs: list[RunData]
    skipped: dict[str, str]  # run name -> why
    warnings: list[str]
    repeated_seeds: dict[str, list[str]] = field(default_factory=dict)  # group -> runs

    @property
    def learners(self) -> list[str]:
        """The groups present (a learner's name, or its name and what sets the group apart),
        learners in the paper's order, unknown names after them."""
        order = {name: k for k, name in enumerate(LEARNER_ORDER)}
        groups = {(r.learner, r.group) for r in self.runs}
        return [g for _, g in sorted(groups, key=lambda lg: (order.get(lg[0], len(order)),
                                                             lg[0], lg[1] != lg[0], lg[1]))]

    def runs_of(self, group: str) -> list[RunData]:
        return sorted((r for r in self.runs if r.group == group), key=lambda r: r.seed)


def _point(values: np.ndarray) -> np.ndarray:
    return values[:OUTCOME_SIZE] if len(values) >= OUTCOME_SIZE else np.full(OUTCOME_SIZE, np.nan)


def _read_run(run_dir: Path) -> tuple[dict[str, np.ndarray], list[str]]:
    """The validated records of every segment of a run, as the columns the analysis needs."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = load_run_folder(run_dir, topics=_WANTED)
    notes = [str(w.message) for w in caught if issubclass(w.category, BagReadWarning)]
    records = {name: getattr(run, name) for name in _WANTED}
    records["demonstrations"] = run.learner_demonstrations
    return _columns(records), notes


def _columns(records: dict[str, list]) -> dict[str, np.ndarray]:
    moves = [m for m in records["movements"] if m.process != PROCESS_EVALUATION]
    evals: dict[int, float] = {}
    latest: dict[int, object] = {}
    for e in records["evaluations"]:
        evals[e.movement_index] = e.mean_distance  # a repeated point: the latest wins
        latest[e.movement_index] = e
    maps: dict[int, RegionMapRecord] = {}
    for m in records["region_map"]:
        maps[m.movement_index] = m  # the state after the last change at that count
    map_keys = sorted(maps)
    leaves = [[r for r in maps[k].regions if r.is_leaf] for k in map_keys]
    flat = [r for group in leaves for r in group]
    status = records["run_status"]
    asks = records.get("help_requests", [])
    chosen = [g for g in records.get("goals", []) if g.strategy]
    return {
        "movement_index": np.array([m.index for m in moves], dtype=np.int64),
        "process": np.array([m.process for m in moves], dtype=np.uint8),
        "status": np.array([m.status for m in moves], dtype=np.uint8),
        "outcome": np.array([_point(m.outcome) for m in moves]).reshape(-1, OUTCOME_SIZE),
        "eval_index": np.array(sorted(evals), dtype=np.int64),
        "eval_mean": np.array([evals[k] for k in sorted(evals)], dtype=float),
        "demo_index": np.array([d.movement_index for d in records["demonstrations"]],
                               dtype=np.int64),
        "demo_outcome": np.array([_point(d.outcome) for d in records["demonstrations"]]
                                 ).reshape(-1, OUTCOME_SIZE),
        "demo_source": np.array([d.source for d in records["demonstrations"]], dtype=str),
        **_goal_by_goal([latest[k] for k in sorted(latest)]),
        "map_index": np.array(map_keys, dtype=np.int64),
        "map_offsets": np.concatenate([[0], np.cumsum([len(g) for g in leaves])]
                                      ).astype(np.int64),
        "leaf_lower": np.array([_point(r.lower) for r in flat]).reshape(-1, OUTCOME_SIZE),
        "leaf_upper": np.array([_point(r.upper) for r in flat]).reshape(-1, OUTCOME_SIZE),
        "leaf_interest": np.array([r.interest for r in flat], dtype=float),
        "ask_index": np.array([a.movement_index for a in asks], dtype=np.int64),
        "ask_teacher": np.array([a.teacher for a in asks], dtype=str),
        "ask_content": np.array([a.content for a in asks], dtype=str),
        "ask_goal": np.array([_point(a.goal) for a in asks]).reshape(-1, OUTCOME_SIZE),
        "choice_index": np.array([g.movement_index for g in chosen], dtype=np.int64),
        "choice_strategy": np.array([g.strategy for g in chosen], dtype=str),
        "choice_mode": np.array([g.mode for g in chosen], dtype=np.uint8),
        "budget": np.array(max((s.total_movements for s in status), default=-1)),
        "final_state": np.array(status[-1].state if status else -1),
    }


def _goal_by_goal(evaluations: list) -> dict[str, np.ndarray]:
    """Each evaluation's distances goal by goal (E, G), and the last evaluation's goals (G, 2):
    what the pages' goal groups need, without reading the bag again."""
    if not evaluations:
        return {"eval_distances": np.zeros((0, 0)), "eval_goals": np.zeros((0, OUTCOME_SIZE))}
    goals = np.asarray(evaluations[-1].goals, float).reshape(-1, OUTCOME_SIZE)
    rows = np.full((len(evaluations), len(goals)), np.nan)
    for row, e in zip(rows, evaluations, strict=True):
        same = np.asarray(e.goals, float).reshape(-1, OUTCOME_SIZE)
        if same.shape == goals.shape and np.array_equal(same, goals) \
                and len(e.distances) == len(goals):
            row[:] = np.asarray(e.distances, float)
    return {"eval_distances": rows, "eval_goals": goals}


def bag_fingerprint(run_dir: Path) -> str:
    """Names, sizes and mtimes of every file of every segment (and of params.yaml, which sets
    the validation limits): any rewrite or a new segment changes it."""
    parts = [f"v{CACHE_VERSION}"]
    files = [f for segment in segments(run_dir) for f in segment.rglob("*") if f.is_file()]
    if (run_dir / "params.yaml").is_file():
        files.append(run_dir / "params.yaml")
    for file in sorted(files):
        info = file.stat()
        parts.append(f"{file.relative_to(run_dir)}:{info.st_size}:{info.st_mtime_ns}")
    return "|".join(parts)


def _load_cache(cache: Path, fingerprint: str) -> tuple[dict[str, np.ndarray], list[str]] | None:
    try:
        with np.load(cache, allow_pickle=False) as data:
            if str(data["fingerprint"]) != fingerprint:
                return None
            columns = {k: data[k] for k in data.files if k not in ("fingerprint", "notes")}
            return columns, [str(n) for n in data["notes"]]
    except (OSError, KeyError, ValueError):
        return None  # missing, stale format or damaged: read the bag again


def _save_cache(cache: Path, fingerprint: str, columns: dict[str, np.ndarray],
                notes: list[str], warn: Warn) -> None:
    tmp = cache.with_name(f".{cache.name}.{os.getpid()}.tmp.npz")
    try:
        np.savez_compressed(tmp, fingerprint=np.array(fingerprint),
                            notes=np.array(notes, dtype=str), **columns)
        os.replace(tmp, cache)  # atomic: a concurrent reader never sees half a file
    except OSError as error:
        tmp.unlink(missing_ok=True)
        warn(f"could not write the cache {cache} ({error}): the next analysis re-reads the bag")


def read_metadata(run_dir: Path, warn: Warn = _default_warn) -> dict:
    """metadata.yaml, with the machine a sweep made the run on (its sweep_run.yaml) when the
    metadata does not say."""
    meta = run_dir / "metadata.yaml"
    if not meta.exists():
        return {}
    try:
        data = yaml.safe_load(meta.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as error:
        warn(f"{meta} is unreadable ({str(error).splitlines()[0]}): using the folder name")
        return {}
    if not isinstance(data, dict):
        return {}
    made_on = _sweep_machine(run_dir)
    if made_on and "machine" not in data:
        data["machine"] = made_on
    return data


def _sweep_machine(run_dir: Path) -> str | None:
    try:
        record = yaml.safe_load((run_dir / "sweep_run.yaml").read_text(encoding="utf-8"))
        found = record["node"]["machine"]
    except (OSError, yaml.YAMLError, KeyError, TypeError):
        return None
    return found if isinstance(found, str) else None


def load_run_data(run_dir: Path, use_cache: bool = True, warn: Warn = _default_warn
                  ) -> RunData | None:
    """One run's arrays, from its cache when the bag did not change; None when unusable."""
    run_dir = Path(run_dir)
    name = run_dir.name
    metadata = read_metadata(run_dir, warn)
    match = _RUN_NAME.match(name)
    learner = metadata.get("learner") or (match["learner"] if match else None)
    seed = metadata.get("seed", int(match["seed"]) if match else None)
    if not isinstance(learner, str) or not isinstance(seed, int):
        warn(f"{run_dir}: neither metadata.yaml nor the folder name gives learner and seed: "
             "skipped")
        return None
    bag = run_dir / "bag"
    if not bag.exists():
        warn(f"{run_dir}: no bag/ folder: skipped")
        return None
    fingerprint = bag_fingerprint(run_dir)
    cache = run_dir / CACHE_NAME
    cached = _load_cache(cache, fingerprint) if use_cache else None
    if cached is None:
        try:
            columns, notes = _read_run(run_dir)
        except (NotABagError, OSError) as error:
            warn(f"{bag}: unreadable, run skipped: {error}")
            return None
        except Exception as error:  # a damaged bag must not stop the study
            warn(f"{bag}: reading failed, run skipped: {type(error).__name__}: {error}")
            return None
        _save_cache(cache, fingerprint, columns, notes, warn)
    else:
        columns, notes = cached
    for note in notes:
        warn(f"{name}: {note}")
    scalars = {k: int(columns.pop(k)) for k in ("budget", "final_state")}
    run = RunData(name=name, path=run_dir, learner=learner, seed=seed, metadata=metadata,
                  warnings=list(notes), **columns, **scalars)
    if not len(run.movement_index) and not len(run.eval_index):
        warn(f"{bag}: no movement and no evaluation could be read: run skipped")
        return None
    if metadata and not run.finished:
        short = " but its recordings end early" if metadata.get("outcome") == "finished" else ""
        warn(f"{name}: run not finished (outcome {metadata.get('outcome', 'unknown')!r}{short}, "
             f"{run.movements_done}/{run.total_movements} movements): using what it recorded")
    return run


def discover_runs(study_dir: Path) -> list[Path]:
    """Run folders: those holding a bag/ or a metadata.yaml (the folder itself if it is one)."""
    study_dir = Path(study_dir)
    if (study_dir / "bag").is_dir():
        return [study_dir]
    return sorted(p for p in study_dir.iterdir()
                  if p.is_dir() and ((p / "bag").is_dir() or (p / "metadata.yaml").exists()))


def load_study(study_dir: str | Path, use_cache: bool = True, warn: Warn = _default_warn,
               progress: Callable[[str], None] | None = None) -> Study:
    """Every usable run of the study; `progress(name)` is called after each run is loaded."""
    study_dir = Path(study_dir)
    if not study_dir.is_dir():
        raise FileNotFoundError(f"{study_dir} is not a folder")
    collected: list[str] = []

    def note(message: str) -> None:
        collected.append(message)
        warn(message)

    runs: list[RunData] = []
    skipped: dict[str, str] = {}
    for run_dir in discover_runs(study_dir):
        before = len(collected)
        run = load_run_data(run_dir, use_cache, note)
        if run is None:
            skipped[run_dir.name] = collected[-1] if len(collected) > before else "unusable"
        else:
            runs.append(run)
        if progress:
            progress(run_dir.name)
    repeated = group_runs(runs, note)
    return Study(study_dir, runs, skipped, collected, repeated)


def _shown(value) -> str:
    return str(value) if not isinstance(value, float) else f"{value:g}"


def _usual_values(conditions: list[dict], keys: list[str]) -> dict[str, object]:
    """Per key, the value more common among the runs than every other; a key whose most
    common values tie has none (every run is then named by its value)."""
    usual: dict[str, object] = {}
    for k in keys:
        counts: dict[str, tuple[int, object]] = {}
        for c in conditions:
            n, _ = counts.get(repr(c.get(k)), (0, c.get(k)))
            counts[repr(c.get(k))] = (n + 1, c.get(k))
        ranked = sorted(counts.values(), key=lambda nv: -nv[0])
        if len(ranked) == 1 or ranked[0][0] > ranked[1][0]:
            usual[k] = ranked[0][1]
    return usual


def group_runs(runs: list[RunData], warn: Warn = _default_warn) -> dict[str, list[str]]:
    """Label each run with the group it may be pooled in; return the groups in which a seed
    repeats (group -> run names). Runs of a learner that differ in anything but the settings
    outside the run (NOT_THE_RUN) go to separate groups, labelled by the values that tell
    them apart."""
    by_learner: dict[str, list[RunData]] = {}
    for run in runs:
        by_learner.setdefault(run.learner, []).append(run)
    for learner, members in by_learner.items():
        conditions = [run.condition for run in members]
        keys = sorted({k for c in conditions for k in c})
        differing = [k for k in keys if len({repr(c.get(k)) for c in conditions}) > 1]
        usual = _usual_values(conditions, differing)
        for run, c in zip(members, conditions, strict=True):
            # Named by what sets it apart from the learner's usual runs (in a sweep, the
            # paper's default setting that every block shares): "sgim-d [timing=on-request]".
            shown = [k for k in differing
                     if k not in usual or repr(c.get(k)) != repr(usual[k])]
            run.group = learner if not shown else (
                f"{learner} [" + ", ".join(f"{k}={_shown(c.get(k))}" for k in shown) + "]")
        if differing:
            groups: dict[str, list[str]] = {}
            for run in members:
                groups.setdefault(run.group, []).append(str(run.seed))
            plain = ", ".join(f"{k}={_shown(v)}" for k, v in usual.items())
            warn(f"{learner}: runs differ in {', '.join(differing)}; not pooled, analysed as "
                 + "; ".join(f"'{g}' ({plain + '; ' if g == learner else ''}seeds "
                             f"{', '.join(s)})" for g, s in groups.items()))
    repeated: dict[str, list[str]] = {}
    seen: dict[tuple[str, int], str] = {}
    for run in sorted(runs, key=lambda r: r.name):
        key = (run.group, run.seed)
        if key in seen:
            repeated.setdefault(run.group, [seen[key]]).append(run.name)
        else:
            seen[key] = run.name
    for group, names in repeated.items():
        warn(f"'{group}': runs {', '.join(names)} share a seed: not independent samples")
    return repeated
