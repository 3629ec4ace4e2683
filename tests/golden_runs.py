"""Digests of reference runs whose movements must be the same on every x86-64 machine.

The settings are those of tests/ros/test_graph_runs.py (fishing, 300 movements, evaluations
every 100, the teacher every 50), seed 0; test_graph_runs.py makes them with the runner and
through the graph, test_portable.py with the runner under other BLAS kernels and SIMD levels,
and all must give these digests bit for bit, whatever CPU model, BLAS kernel or numpy SIMD
level runs them (core/portable.py). A change of the learner or the world that changes its
movements changes them: update them in the same commit, with the reason.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np

SEED = 0
MOVEMENTS, EVAL_EVERY, PERIOD = 300, 100, 50
TOLERANCE = {"sgim-d": 8.0, "demo-only": 0.7}
"""The teacher's tolerance, in noise units, per learner (test_graph_runs.py says why)."""

DIGESTS = {
    "sgim-d": "1a7a07c077c80c9476d6",
    "saggriac": "c02dfe67fef57ad98312",
    "random-goals": "6ee1eb7b9d25d6a03f13",
    "demo-only": "bd8bd4300b2b00051a76",
    "random": "927f42c8fcb6b0f806de",
    "sgim-acts": "ff626c0e2d7334134e16",
}


def movements_digest(moves: Iterable[tuple[Sequence[float], int, int, Sequence[float] | None]]
                     ) -> str:
    """sha256 of (action, process, status, outcome) of every movement, in order; the outcome
    only when the status says the movement gave one."""
    h = hashlib.sha256()
    for action, process, status, outcome in moves:
        h.update(np.asarray(action, dtype="<f8").tobytes())
        h.update(bytes([int(process), int(status)]))
        if int(status) == 0:
            h.update(np.asarray(outcome, dtype="<f8").tobytes())
    return h.hexdigest()[:20]


def runner_digest(records: list[dict]) -> str:
    """The digest of a runner's records (core/runner.py)."""
    from sgim_nodes.core.environment import PROCESS_CODES

    return movements_digest(
        (r["action"], PROCESS_CODES[r["label"]], r["status"], r["outcome"])
        for r in records if r["type"] == "movement")


def bag_digest(movements) -> str:
    """The digest of a bag's Movement records."""
    return movements_digest((m.action, m.process, m.status, m.outcome) for m in movements)


def runner_records(learner: str, seed: int = SEED, movements: int = MOVEMENTS,
                   eval_every: int = EVAL_EVERY, **teacher) -> list[dict]:
    """The runner's records of the reference run of ``learner`` (or of another budget)."""
    from sgim_nodes.core.learner_registry import make_learner
    from sgim_nodes.core.runner import build_world, run
    from sgim_nodes.core.social_config import SocialConfig

    world = build_world("fishing", seed)
    if learner == "sgim-acts":  # its teachers answer requests (core/acts_runner.py)
        from sgim_nodes.core.acts_runner import experts_for, run_acts

        experts = experts_for("fishing", world, seed)
        made = make_learner(learner, world.env.action_dim, world.env.outcome_dim, seed,
                            scale=world.scale, teachers=tuple(experts))
        records = []
        run_acts(made, world, movements, eval_every, experts, records.append)
        return records
    made = make_learner(learner, world.env.action_dim, world.env.outcome_dim, seed,
                        scale=world.scale)
    records: list[dict] = []
    social = SocialConfig(demonstration_period=PERIOD,
                          tolerance_noise=TOLERANCE.get(learner, 1.0), **teacher)
    run(made, world, movements, eval_every, seed, records.append, social)
    return records


def runner_records_later(learner: str, **settings) -> Future[list[dict]]:
    """``runner_records`` in a process of its own, started now: a graph test starts it before
    its graph run and takes ``.result()`` after, so that the runner uses a core the graph's
    start-up leaves idle. Spawned, not forked: the test process holds rclpy's threads."""
    executor = ProcessPoolExecutor(max_workers=1, mp_context=get_context("spawn"))
    try:
        return executor.submit(runner_records, learner, **settings)
    finally:
        executor.shutdown(wait=False)  # the submitted run goes on; the process then ends
