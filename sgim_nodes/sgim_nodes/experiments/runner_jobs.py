"""Runs of the single-process runner for pinned experiments, with measurements inside them.

Why the runner and not the graph: the analytic arms (core/planar_arm.py) have no simulator
node, and some figures need the learner's own objects while it runs (probes.py) or after
(its final memory, for the inverse model against the nearest neighbour). The runner makes
the graph's very movements (tests/ros/test_graph_runs.py), so nothing is lost.

A run's result is one JSON file, written whole, holding its learner fingerprint: a runs
folder resumes by skipping the files whose fingerprint is today's.

    runs:                          # the experiment file's runs (pinned.py)
      movements: 5000
      eval_every: 250
      seeds: 10                    # 0..9, or a list, or {first, count}
      goals: benchmark             # or validation: other points of the same cells
      set: {}                      # LearnerConfig values for every learner
      teacher_rule: ability
      grid:
        - world: [arm-7, arm-20]
          learner: [random, random-goals, saggriac, sgim-d]
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from sgim_nodes.core import portable
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.learner_registry import compared_names, make_learner
from sgim_nodes.core.learners import GoalBabblingLearner
from sgim_nodes.core.planar_arm import ARMS, reach_of
from sgim_nodes.core.runner import World, build_world, run
from sgim_nodes.core.social_config import SocialConfig
from sgim_nodes.core.teaching import DEFAULT_REACHED_RULE, REACHED_RULES
from sgim_nodes.experiments.probes import Probe, ReachMap
from sgim_nodes.provenance import fingerprint as fp

WORLDS = (*ARMS, "fishing")
GOAL_SETS = {"benchmark": 0, "validation": 7}
FRAME = 500  # movements per frame of the probes' mode-1 shares
SAME_MEMORY_CASTS = 10
"""Casts per goal of the fishing world's same-memory comparison: with 2 its verdict flipped
on ties (a repeat's difference has a standard deviation of 0.002-0.005); 10 halves that."""
KEYS = ("movements", "eval_every", "seeds", "goals", "set", "teacher_rule", "grid")


@dataclass(frozen=True)
class RunnerJob:
    world: str
    learner: str
    seed: int
    movements: int
    eval_every: int
    goals: str = "benchmark"
    config: tuple[tuple[str, Any], ...] = ()  # LearnerConfig values, sorted by name
    teacher_rule: str = DEFAULT_REACHED_RULE

    @property
    def name(self) -> str:
        return f"{self.world}-{self.learner}-seed{self.seed}"

    @property
    def learner_config(self) -> LearnerConfig:
        return LearnerConfig(**dict(self.config))

    def fingerprint(self) -> fp.Fingerprint:
        options = {"movements": self.movements, "eval_every": self.eval_every,
                   "goals": self.goals, "teacher_rule": self.teacher_rule}
        return fp.fingerprint(fp.runner_parameters(self.world, self.learner,
                                                   asdict(self.learner_config), options))


def _as_list(value: Any) -> list:
    return list(value) if isinstance(value, list) else [value]


def _seeds(value: Any, where: str) -> list[int]:
    from sgim_nodes.sweep.sweep_file import SweepFileError, _seeds

    try:
        return _seeds(value, where)
    except SweepFileError as error:
        raise ValueError(str(error)) from None


def expand_jobs(runs: Mapping[str, Any], where: str) -> list[RunnerJob]:
    """Every job of an experiment's ``runs`` (ValueError naming the problem)."""
    unknown = sorted(set(runs) - set(KEYS))
    if unknown:
        raise ValueError(f"{where}: unknown runner setting(s) {', '.join(unknown)}; "
                         f"the settings are {', '.join(KEYS)}")
    seeds = _seeds(runs.get("seeds", 1), where)
    config = dict(runs.get("set") or {})
    try:
        LearnerConfig(**config)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{where}: set: {error}") from None
    goals, rule = runs.get("goals", "benchmark"), runs.get("teacher_rule", DEFAULT_REACHED_RULE)
    if goals not in GOAL_SETS or rule not in REACHED_RULES:
        raise ValueError(f"{where}: goals must be one of {', '.join(GOAL_SETS)} and "
                         f"teacher_rule one of {', '.join(REACHED_RULES)}")
    movements, eval_every = runs.get("movements", 5000), runs.get("eval_every", 250)
    if not all(isinstance(v, int) and not isinstance(v, bool) and v >= 1
               for v in (movements, eval_every)):
        raise ValueError(f"{where}: movements and eval_every must be integers >= 1")
    jobs = []
    for b, block in enumerate(runs.get("grid") or [{}]):
        here = f"{where}, grid block {b + 1}"
        if not isinstance(block, Mapping) or set(block) != {"world", "learner"}:
            raise ValueError(f"{here}: a block names 'world' and 'learner', and only them")
        for world in _as_list(block["world"]):
            for learner in _as_list(block["learner"]):
                if world not in WORLDS or learner not in compared_names():
                    raise ValueError(f"{here}: world must be one of {', '.join(WORLDS)} "
                                     f"and learner one of {', '.join(compared_names())}")
                jobs += [RunnerJob(world, learner, seed, movements, eval_every, goals,
                                   tuple(sorted(config.items())), rule) for seed in seeds]
    names = [job.name for job in jobs]
    if len(set(names)) != len(names):
        raise ValueError(f"{where}: a world, learner and seed appear twice")
    return jobs


def goals_for(name: str, kind: str) -> tuple[np.ndarray | None, np.ndarray]:
    """(actions, goals): on the arms one reachable point per reachable cell of the benchmark
    grid with the posture that reaches it exactly (``validation``: other points of the
    cells); on fishing its packaged benchmark goals, or other points of their cells."""
    if name == "fishing":
        from sim_bridge.data_files import load_benchmark_goals, load_reachable_map
        from sim_bridge.tools.make_benchmark_set import validation_goals

        if kind == "validation":
            return None, np.asarray(validation_goals(load_reachable_map()), float)
        return None, np.asarray(load_benchmark_goals(), float)
    spec = ARMS[name]
    return reach_of(spec.make(0, noise=0.0), spec.cells, GOAL_SETS[kind]).reached_points()


@cache
def reach_map(name: str) -> ReachMap:
    """Never-reachable cells of the world's box on a 40 x 40 grid (arms: planar_arm's flood
    fill; fishing: the cells whose centre is on land, where no cast ever lands)."""
    if name == "fishing":
        from sim_bridge.lake import is_water
        from sim_bridge.scaling import outcome_to_world

        centres = (np.stack(np.meshgrid(np.arange(40), np.arange(40), indexing="ij"), -1)
                   + 0.5) / 40 * 2.0 - 1.0
        water = is_water(outcome_to_world(centres.reshape(-1, 2))).reshape(40, 40)
        return ReachMap(np.full(2, -1.0), np.full(2, 1.0), water)
    arm = ARMS[name].make(0, noise=0.0)
    return ReachMap(np.asarray(arm.box[0], float), np.asarray(arm.box[1], float),
                    reach_of(arm, 40).reached)


def floor(name: str, kind: str, casts: int = 100) -> tuple[float, np.ndarray]:
    """The best achievable mean error: on the arms, per goal the posture that reaches it
    exactly, cast ``casts`` times with the arm's noise; on fishing, the floor shipped with
    the benchmark set (NaN for the validation goals, which have none)."""
    if name == "fishing":
        if kind != "benchmark":
            return float("nan"), np.empty(0)
        from sim_bridge.data_files import load_floor

        per_goal = np.asarray(load_floor().per_goal, float).ravel()
        return float(per_goal.mean()), per_goal
    noisy = ARMS[name].make(123)
    actions, goals = goals_for(name, kind)
    per_goal = np.array([np.mean([portable.norm(noisy.execute(a).outcome - g)
                                  for _ in range(casts)])
                         for a, g in zip(actions, goals, strict=True)])
    return float(per_goal.mean()), per_goal


def same_memory(world: World, learner, name: str, casts: int = SAME_MEMORY_CASTS
                ) -> dict[str, float]:
    """The final memory evaluated with the learner's inverse model and with the plain nearest
    neighbour on the same goals: noise-free on the arms, ``casts`` casts per goal in a fresh
    evaluation world on fishing (the same seed for both)."""
    from sgim_nodes.core.evaluator import EVALUATION_SEED_OFFSET, Evaluator
    from sgim_nodes.core.inverse_model import InverseModel
    from sgim_nodes.core.learners import inverse_model_for

    models = {"ours": inverse_model_for(learner.memory, learner.config, learner.scale),
              "nearest": InverseModel(learner.memory, "nearest")}
    out = {}
    for label, model in models.items():
        if name in ARMS:
            arm = ARMS[name].make(0, noise=0.0)
            out[label] = float(np.mean([portable.norm(arm.forward(model(g)) - g)
                                        for g in world.goals]))
        else:
            fresh = build_world(name, 10_000 + EVALUATION_SEED_OFFSET)
            ev = Evaluator(fresh.eval_env, world.goals, world.scale.diagonal)
            out[label] = float(np.mean([ev.evaluate(model).mean_distance
                                        for _ in range(casts)]))
    return out


def run_job(job: RunnerJob, measures: bool = True) -> dict[str, Any]:
    """One run: its error curve, demonstrations, same-memory comparison and probes (the last
    two only with `measures`: a check of the curve alone needs neither)."""
    world = build_world(job.world, job.seed)
    world.goals = goals_for(job.world, job.goals)[1]
    learner = make_learner(job.learner, world.env.action_dim, world.env.outcome_dim, job.seed,
                           job.learner_config, world.scale)
    forward = ARMS[job.world].make(0, noise=0.0).forward if job.world in ARMS else None
    probe = Probe(learner, forward) if isinstance(learner, GoalBabblingLearner) else None
    start = time.perf_counter()
    curve = run(learner, world, job.movements, job.eval_every, job.seed, lambda record: None,
                SocialConfig(reached_rule=job.teacher_rule))
    out = {"job": asdict(job), "name": job.name, "fingerprint": job.fingerprint().to_dict(),
           "curve": [float(v) for v in curve], "final": float(curve[-1]),
           "seconds": time.perf_counter() - start,
           "n_demonstrations": learner.memory.labels.count("demonstration")}
    if measures:
        out["same_memory"] = same_memory(world, learner, job.world)
    if probe is not None and measures:
        out["probe"] = probe.summary(FRAME, job.movements, reach_map(job.world))
    return out


def result_path(runs_dir: Path, job: RunnerJob) -> Path:
    return runs_dir / f"{job.name}.json"


def read_result(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def write_result(path: Path, result: dict[str, Any]) -> None:
    """Whole or not at all: a killed writer leaves no half file that looks finished."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(result, default=_plain))
    tmp.replace(path)


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON")
