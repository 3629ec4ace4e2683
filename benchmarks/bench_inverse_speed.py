"""What the inverse model costs: a learner's whole run, with the fit cache and without it.

The local-linear inverse model fits a linear model around each of its l_max candidates for
every goal; core/fit_cache.py keeps each fit until a new pair lands within its radius. This
runs the same learner, seed and world twice in the single-process runner, once with the cache
and once with a cache of one fit (a refit almost every time), and prints both wall times, the
cache's hit rate, and whether the two runs made the same movements (they must: the cache
answers exactly what a refit answers). Then the evaluator's share (the graph's evaluator and
teacher hold a model of their own): the run's memory replayed pair by pair, the inverse model
asked for every benchmark goal after each 250 pairs, CPU time with and without the cache.

Run:  .venv/bin/python benchmarks/bench_inverse_speed.py                  (arm-20, 5000)
      .venv/bin/python benchmarks/bench_inverse_speed.py --world arm-7 --learner saggriac
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "sgim_nodes"), str(REPO / "sim_bridge")]

from sgim_nodes.core.config import LearnerConfig  # noqa: E402
from sgim_nodes.core.fit_cache import FitCache  # noqa: E402
from sgim_nodes.core.inverse_model import InverseModel  # noqa: E402
from sgim_nodes.core.learner_registry import (  # noqa: E402
    GOAL_BABBLING,
    SGIM_D,
    kinds,
    make_learner,
)
from sgim_nodes.core.learners import build_memory  # noqa: E402
from sgim_nodes.core.planar_arm import ARMS  # noqa: E402
from sgim_nodes.core.runner import build_world, run  # noqa: E402


def with_capacity(model: InverseModel, capacity: int | None) -> None:
    """Give ``model`` a fit cache of ``capacity`` fits (1: a refit almost every time); None
    keeps its default cache."""
    if capacity is not None:
        model.fits = FitCache(model.memory, model.local_radius, model.local_neighbours,
                              capacity)


def one_run(world_name: str, learner_name: str, seed: int, movements: int,
            capacity: int | None) -> tuple[float, np.ndarray, FitCache, np.ndarray]:
    world = build_world(world_name, seed)
    learner = make_learner(learner_name, world.env.action_dim, world.env.outcome_dim, seed,
                           LearnerConfig(), world.scale)
    model = learner.inverse_model
    with_capacity(model, capacity)
    start = time.perf_counter()
    run(learner, world, movements, 250, seed, lambda record: None)
    return (time.perf_counter() - start, learner.memory.actions.copy(), model.fits,
            learner.memory.outcomes.copy())


def evaluator_cpu(world_name: str, actions: np.ndarray, outcomes: np.ndarray,
                  capacity: int | None, every: int = 250) -> tuple[float, int]:
    """CPU seconds of the inverse model over the world's goals after each ``every`` pairs of
    the memory replayed in order, as an evaluator node receiving the movements asks it."""
    world = build_world(world_name, 0)
    memory, model = build_memory(LearnerConfig(), actions.shape[1], outcomes.shape[1],
                                 world.scale)
    with_capacity(model, capacity)
    spent, evaluations = 0.0, 0
    for i, (a, y) in enumerate(zip(actions, outcomes, strict=True)):
        memory.add(a, y)
        if (i + 1) % every == 0:
            start = time.process_time()
            for goal in world.goals:
                model(goal)
            spent += time.process_time() - start
            evaluations += 1
    return spent, evaluations


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--world", default="arm-20", choices=[*ARMS, "fishing"])
    p.add_argument("--learner", default=SGIM_D,
                   choices=[k.name for k in kinds() if k.host == GOAL_BABBLING])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--movements", type=int, default=5000)
    a = p.parse_args(argv)
    if a.movements < 1:
        p.error("--movements must be >= 1")
    print(f"{a.learner} on {a.world}, seed {a.seed}, {a.movements} movements, "
          "single-process runner")
    cached_s, cached_actions, cache, outcomes = one_run(a.world, a.learner, a.seed,
                                                        a.movements, None)
    asked = cache.hits + cache.misses
    print(f"  with the fit cache:   {cached_s:7.1f} s  ({cache.hits} of {asked} fits from the "
          f"cache, {cache.hits / max(asked, 1):.0%})")
    fresh_s, fresh_actions, _, _ = one_run(a.world, a.learner, a.seed, a.movements, 1)
    print(f"  refitting every time: {fresh_s:7.1f} s")
    same = (cached_actions.shape == fresh_actions.shape
            and np.array_equal(cached_actions, fresh_actions))
    print(f"  speed-up {fresh_s / cached_s:.2f}; same movements: {same}")
    with_cache, n = evaluator_cpu(a.world, cached_actions, outcomes, None)
    without, _ = evaluator_cpu(a.world, cached_actions, outcomes, 1)
    print(f"evaluator's inverse model, {n} evaluations of the run's memory as it grew: "
          f"{with_cache:.2f} s of CPU with the cache, {without:.2f} s refitting")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
