"""Check shipped runs by making them again: `ros_ws/reproduce.sh NAME --verify K`.

K of the experiment's shipped runs, drawn with a seed the command prints (give it back with
--verify-seed to check the same runs), are made again, by the single-process runner (the same
movements as the graph for the same settings and seed), or through the graph with --graph;
each is compared with its run table movement for movement: what each movement was (the
learner's own, an imitation, a demonstration), whether it landed and where, to the bit; then
the evaluations and the demonstrations taken. The first difference is named.

A runner or world experiment ships result files rather than run tables: K of its jobs are made
again and their results compared, field by field (the time a job took aside).

`--verify-movements N` checks each run's first N movements only (a world's chunk: its first N
casts), made again at that length: a run's first movements do not depend on its budget, so
this is the quick check (a runner job's error curve is then compared at its evaluations
before N; the figures made from its whole run are not).
"""

from __future__ import annotations

import dataclasses
import json
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sgim_nodes.analysis.study import OUTCOME_SIZE, RunData, load_run_data
from sgim_nodes.experiments.pinned import Experiment
from sgim_nodes.sweep.sweep_file import RunSpec

ENV = "fishing"
RUN_EXPERIMENT = Path(__file__).resolve().parents[3] / "ros_ws" / "run_experiment.sh"
COMPARED = ("process", "status", "outcome", "eval_index", "eval_mean", "demo_index")
"""The columns a remade run must give to the bit (RunData's)."""


@dataclass(frozen=True)
class Verified:
    name: str
    seconds: float
    difference: str  # empty: the same run

    @property
    def same(self) -> bool:
        return not self.difference


def config_of(spec: RunSpec):
    """The LearnerConfig a graph run of `spec` gives its learner: the defaults and the
    experiment's learner parameters."""
    import dataclasses

    import yaml

    from sgim_nodes.core.config import LearnerConfig

    fields = {f.name for f in dataclasses.fields(LearnerConfig)}
    return LearnerConfig(**{name: yaml.safe_load(text) for name, text in spec.params
                            if name in fields})


def social_of(spec: RunSpec):
    """The runner's SocialConfig for a graph run: its period and the social parameters."""
    import dataclasses

    import yaml

    from sgim_nodes.core.social_config import SocialConfig
    from sgim_nodes.core.teacher_turns import turn_specs

    fields = {f.name for f in dataclasses.fields(SocialConfig)}
    given: dict[str, Any] = {k: yaml.safe_load(v) for k, v in spec.params if k in fields}
    if isinstance(given.get("teacher_turns"), str):
        given["teacher_turns"] = turn_specs(ENV, given["teacher_turns"])
    if spec.demonstration_period is not None:
        given["demonstration_period"] = spec.demonstration_period
    return SocialConfig(**given)


@dataclass
class RunnerTwin:
    """What the runner makes a graph run of `spec` with: its world, its learner and, for a
    learner that asks its own teachers, those teachers (None for the others)."""

    spec: RunSpec
    world: Any
    learner: Any
    experts: dict[str, Any] | None

    @classmethod
    def of(cls, spec: RunSpec) -> RunnerTwin:
        from sgim_nodes.core.acts_runner import experts_for
        from sgim_nodes.core.learner_registry import learner_kind, make_learner
        from sgim_nodes.core.runner import build_world

        world = build_world(ENV, spec.seed)
        experts = (experts_for(ENV, world, spec.seed)
                   if learner_kind(spec.learner).chooses_teachers else None)
        learner = make_learner(spec.learner, world.env.action_dim, world.env.outcome_dim,
                               spec.seed, config=config_of(spec), scale=world.scale,
                               teachers=tuple(experts or ()))
        return cls(spec, world, learner, experts)

    def run(self, write: Callable[[dict[str, Any]], None]) -> None:
        """Make the run, each record to `write` (core/runner.py's and acts_runner.py's)."""
        from sgim_nodes.core.acts_runner import run_acts
        from sgim_nodes.core.runner import run

        spec = self.spec
        if self.experts is not None:
            run_acts(self.learner, self.world, spec.movements, spec.eval_every, self.experts,
                     write)
        else:
            run(self.learner, self.world, spec.movements, spec.eval_every, spec.seed, write,
                social_of(spec))


def landing(record: dict[str, Any]) -> list[float]:
    """A movement record's outcome, NaN when the cast gave none (as RunData.outcome)."""
    return record["outcome"] if record["outcome"] is not None else [np.nan] * OUTCOME_SIZE


def runner_columns(spec: RunSpec) -> dict[str, np.ndarray]:
    """The compared columns of `spec`'s run made by the runner."""
    from sgim_nodes.core.environment import PROCESS_CODES

    records: list[dict[str, Any]] = []
    RunnerTwin.of(spec).run(records.append)
    moves = [r for r in records if r["type"] == "movement"]
    evaluations = {int(r["movements"]): float(r["mean_distance"])
                   for r in records if r["type"] == "evaluation"}
    return {
        "process": np.array([PROCESS_CODES[m["label"]] for m in moves], dtype=np.uint8),
        "status": np.array([m["status"] for m in moves], dtype=np.uint8),
        "outcome": np.array([landing(m) for m in moves], dtype=float).reshape(-1, OUTCOME_SIZE),
        "eval_index": np.array(sorted(evaluations), dtype=np.int64),
        "eval_mean": np.array([evaluations[k] for k in sorted(evaluations)], dtype=float),
        "demo_index": _demonstration_counts(records)}


def _demonstration_counts(records: list[dict[str, Any]]) -> np.ndarray:
    """The learner's movement count at each demonstration it took (a periodic teacher's, or
    an expert's answer that showed something: an answer with neither action nor outcome shows
    nothing, as "none there"), as the graph records it."""
    return np.array([r["movement"] for r in records
                     if r["type"] == "demonstration"
                     or (r["type"] == "answer" and r.get("answered")
                         and (r.get("action") is not None or r.get("outcome") is not None))],
                    dtype=np.int64)


def first_unequal(mine: np.ndarray, theirs: np.ndarray) -> int | None:
    """The first row (entry of a 1-D column) where two columns differ, to the bit (NaN equal
    to NaN); the shorter's length when one only stops early; None when they are equal."""
    mine, theirs = np.asarray(mine), np.asarray(theirs)
    same = min(len(mine), len(theirs))
    a, b = mine[:same], theirs[:same]
    equal = (np.isclose(a, b, rtol=0, atol=0, equal_nan=True) if a.dtype.kind == "f"
             else a == b)
    if equal.ndim > 1:
        equal = equal.all(axis=tuple(range(1, equal.ndim)))
    if not equal.all():
        return int(np.flatnonzero(~equal)[0])
    return None if len(mine) == len(theirs) else same


def graph_columns(spec: RunSpec, work: Path, timeout: float) -> dict[str, np.ndarray]:
    """The compared columns of `spec`'s run made again through the graph, in `work`."""
    import subprocess

    argv = [str(RUN_EXPERIMENT), *spec.argv(), "--runs-dir", str(work),
            "--name", spec.name, "--quiet", "--no-markers", "--timeout", str(timeout)]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout + 120)
    if done.returncode != 0:
        raise RuntimeError(f"{spec.name}: the graph run failed (exit {done.returncode}): "
                           f"{(done.stderr or done.stdout).strip()[-400:]}")
    run = load_run_data(work / spec.name, use_cache=False, warn=lambda message: None)
    if run is None:
        raise RuntimeError(f"{spec.name}: the graph run left nothing readable")
    return {name: getattr(run, name) for name in COMPARED}


def cut(columns: Mapping[str, np.ndarray], movements: int | None) -> dict[str, np.ndarray]:
    """Compared columns cut to the first `movements` (None: whole): those movements, and the
    evaluations and demonstrations before the last of them (a run that ends there evaluates
    at its end, and a longer one takes its teacher's turn there)."""
    columns = {name: np.asarray(columns[name]) for name in COMPARED}
    if movements is None:
        return columns
    kept_evaluations = columns["eval_index"] < movements
    return {**{name: columns[name][:movements] for name in ("process", "status", "outcome")},
            "eval_index": columns["eval_index"][kept_evaluations],
            "eval_mean": columns["eval_mean"][kept_evaluations],
            "demo_index": columns["demo_index"][columns["demo_index"] < movements]}


def shipped_columns(run: RunData, movements: int | None = None) -> dict[str, np.ndarray]:
    """A shipped run's compared columns, cut to its first `movements` (None: whole)."""
    return cut({name: getattr(run, name) for name in COMPARED}, movements)


def difference(made: Mapping[str, np.ndarray], shipped: RunData | Mapping[str, np.ndarray],
               columns: Sequence[str] = COMPARED) -> str:
    """The first way `made` differs from the shipped run (or its columns, as
    shipped_columns gives them); empty when it does not."""
    if isinstance(shipped, RunData):
        shipped = shipped_columns(shipped)
    for name in columns:
        mine, theirs = np.asarray(made[name]), np.asarray(shipped[name])
        if mine.shape != theirs.shape:
            return f"{name}: {len(mine)} made, {len(theirs)} shipped"
        k = first_unequal(mine, theirs)
        if k is not None:
            where = f"movement {k + 1}" if name in ("process", "status", "outcome") else \
                f"entry {k}"
            return f"{name} differs first at {where}: {mine[k]} made, {theirs[k]} shipped"
    return ""


def draw(names: Sequence[str], count: int, seed: int) -> list[str]:
    """`count` of `names` (sorted), drawn with `seed`, in their order."""
    names = sorted(names)
    return [names[k] for k in sorted(np.random.default_rng(seed).choice(
        len(names), size=min(count, len(names)), replace=False))] if names else []


def verify(experiment: Experiment, count: int, seed: int, graph: bool,
           say: Callable[[str], None], timeout: float = 3600.0,
           movements: int | None = None) -> list[Verified]:
    """Make `count` shipped runs (or result files) of `experiment` again, drawn with `seed`,
    and compare; `movements`: only each run's first movements, made at that length."""
    if experiment.maker != "graph":
        from sgim_nodes.experiments.shipped import shipped_names

        chosen = draw(list(shipped_names(experiment)), count, seed)
        part = f", first {movements} movements or casts" if movements else ""
        say(f"{experiment.name}: verifying {len(chosen)} of its shipped results (seed {seed}"
            f"{part}): {', '.join(chosen)}")
        return verify_results(experiment, chosen, say, movements)
    from sgim_nodes.experiments.shipped import shipped_runs

    shipped = shipped_runs(experiment)
    chosen = draw(list(shipped), count, seed)
    specs = {s.name: s for s in experiment.graph_runs}
    part = f", first {movements} movements" if movements else ""
    say(f"{experiment.name}: verifying {len(chosen)} of its {len(shipped)} shipped runs (seed "
        f"{seed}, {'through the graph' if graph else 'by the runner'}{part}): "
        f"{', '.join(chosen)}")
    found = []
    for name in chosen:
        began = time.monotonic()
        spec = specs[name]
        if movements is not None:
            spec = dataclasses.replace(spec, movements=min(movements, spec.movements))
        if graph:
            with tempfile.TemporaryDirectory(prefix="sgim-verify-") as work:
                made = graph_columns(spec, Path(work), timeout)
        else:
            made = runner_columns(spec)
        result = Verified(name, time.monotonic() - began,
                          difference(cut(made, movements),
                                     shipped_columns(shipped[name], movements)))
        say(f"{name}: {'the same run' if result.same else result.difference} "
            f"({result.seconds:.0f} s)")
        found.append(result)
    return found


# --- runner and world experiments: their result files ---------------------------------------

def shortened(job, movements: int | None):
    """The job made at `movements` (a runner job's movements, a cast chunk's casts); a world
    probe stays whole. None: the job itself."""
    from sgim_nodes.experiments.runner_jobs import RunnerJob
    from sgim_nodes.experiments.world_jobs import CastChunk

    if movements is None:
        return job
    if isinstance(job, RunnerJob):
        return dataclasses.replace(job, movements=min(movements, job.movements))
    if isinstance(job, CastChunk):
        return dataclasses.replace(job, casts=min(movements, job.casts))
    return job


NOT_RESULTS = ("seconds", "fingerprint", "machine")
"""What a result file says of how it was made, not what was made: its time, the fingerprint
of the code and versions that made it (the stamps say which behaviour that was), and the
machine it was made on."""


def plain(result: Mapping[str, object]) -> dict[str, object]:
    """A result as its file holds it (JSON types, numpy arrays as lists), NOT_RESULTS aside."""
    from sgim_nodes.experiments.runner_jobs import _plain

    return {k: v for k, v in json.loads(json.dumps(result, default=_plain)).items()
            if k not in NOT_RESULTS}


def result_difference(made: Mapping[str, object], shipped: Mapping[str, object],
                      whole: bool) -> str:
    """The first field where a remade result differs from the shipped one; when not
    `whole`, a runner job's error curve and a chunk's points are compared as a prefix."""
    made, shipped = plain(made), plain(shipped)
    if not whole:
        key = "curve" if "curve" in made else "points" if "points" in made else None
        if key is not None:
            mine, theirs = np.asarray(made[key], dtype=float), np.asarray(shipped[key],
                                                                          dtype=float)
            k = first_unequal(mine, theirs[:len(mine)])
            return "" if k is None else f"{key} differs first at entry {k}: {mine[k]} made, " \
                                        f"{theirs[k]} shipped"
    for key in sorted(shipped):  # what the file keeps (a world's keeps no name)
        mine, theirs = made.get(key), shipped[key]
        if key in ("points", "values", "curve") and mine is not None:
            a, b = np.asarray(mine, dtype=float), np.asarray(theirs, dtype=float)
            k = first_unequal(a, b) if a.shape[1:] == b.shape[1:] else 0
            if k is not None:
                return f"{key} differs first at entry {k}"
        elif json.dumps(mine, sort_keys=True) != json.dumps(theirs, sort_keys=True):
            return f"{key}: {str(mine)[:80]} made, {str(theirs)[:80]} shipped"
    return ""


def verify_results(experiment: Experiment, names: Sequence[str], say: Callable[[str], None],
                   movements: int | None = None) -> list[Verified]:
    """Make the named jobs of a runner or world experiment again and compare their results
    with the shipped files; `movements`: each at that length (shortened)."""
    from sgim_nodes.experiments.runner_jobs import RunnerJob
    from sgim_nodes.experiments.shipped import file_jobs, results_folder

    jobs, module = file_jobs(experiment)
    by_name = {job.name: job for job in jobs}
    found = []
    for name in names:
        job = by_name[name]
        short = shortened(job, movements)
        began = time.monotonic()
        if isinstance(job, RunnerJob) and short != job:
            # Its curve up to the last evaluation before its end (a run evaluates again at
            # its end); its end-of-run measures are neither made nor compared.
            made = module.run_job(short, measures=False)
            made["curve"] = made["curve"][:len(range(0, short.movements, job.eval_every))]
        else:
            made = module.run_job(short)
        shipped = module.read_result(results_folder(experiment) /
                                     module.result_path(Path("."), job).name)
        why = ("its shipped file is unreadable" if shipped is None else
               result_difference(made, shipped, short == job))
        result = Verified(name, time.monotonic() - began, why)
        say(f"{name}: {'the same result' if result.same else result.difference} "
            f"({result.seconds:.0f} s)")
        found.append(result)
    return found
