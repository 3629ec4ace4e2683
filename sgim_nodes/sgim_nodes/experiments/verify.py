"""Check shipped runs by making them again: `ros_ws/reproduce.sh NAME --verify K`.

K of the experiment's shipped runs, drawn with a seed the command prints (give it back with
--verify-seed to check the same runs), are made again, by the single-process runner (the same
movements as the graph for the same settings and seed), or through the graph with --graph;
each is compared with its run table movement for movement: what each movement was (the
learner's own, an imitation, a demonstration), whether it landed and where, to the bit; then
the evaluations and the demonstrations taken. The first difference is named.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable, Sequence
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
    an expert's answer that showed something), as the graph records it."""
    return np.array([r["movement"] for r in records
                     if r["type"] == "demonstration"
                     or (r["type"] == "answer" and r.get("answered"))], dtype=np.int64)


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


def difference(made: dict[str, np.ndarray], shipped: RunData,
               columns: Sequence[str] = COMPARED) -> str:
    """The first way `made` differs from the shipped run; empty when it does not."""
    for name in columns:
        mine, theirs = np.asarray(made[name]), np.asarray(getattr(shipped, name))
        if mine.shape != theirs.shape:
            return f"{name}: {len(mine)} made, {len(theirs)} shipped"
        k = first_unequal(mine, theirs)
        if k is not None:
            where = f"movement {k + 1}" if name in ("process", "status", "outcome") else \
                f"entry {k}"
            return f"{name} differs first at {where}: {mine[k]} made, {theirs[k]} shipped"
    return ""


def verify(experiment: Experiment, count: int, seed: int, graph: bool,
           say: Callable[[str], None], timeout: float = 3600.0) -> list[Verified]:
    """Make `count` shipped runs of `experiment` again (drawn with `seed`) and compare."""
    from sgim_nodes.experiments.shipped import shipped_runs

    shipped = shipped_runs(experiment)
    names = sorted(shipped)
    chosen = [names[k] for k in sorted(np.random.default_rng(seed).choice(
        len(names), size=min(count, len(names)), replace=False))] if names else []
    specs = {s.name: s for s in experiment.graph_runs}
    say(f"{experiment.name}: verifying {len(chosen)} of its {len(names)} shipped runs (seed "
        f"{seed}, {'through the graph' if graph else 'by the runner'}): {', '.join(chosen)}")
    found = []
    for name in chosen:
        began = time.monotonic()
        if graph:
            with tempfile.TemporaryDirectory(prefix="sgim-verify-") as work:
                made = graph_columns(specs[name], Path(work), timeout)
        else:
            made = runner_columns(specs[name])
        result = Verified(name, time.monotonic() - began, difference(made, shipped[name]))
        say(f"{name}: {'the same run' if result.same else result.difference} "
            f"({result.seconds:.0f} s)")
        found.append(result)
    return found
