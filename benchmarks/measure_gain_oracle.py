"""Can ANY goal attempt gain on memory when both are judged by noisy outcomes? (issue 10, item 3)

Gain on memory = memory's closest stored outcome to the goal before an attempt, minus the
attempt's best outcome. Both are minima of noisy casts, so memory's side carries a selection
bias (the winner's curse): among many stored casts near a goal, the closest is the luckiest.
This script runs a learner on an analytic arm, then, on its memory at several sizes, gives each
validation goal a PERFECT attempt: the posture that reaches the goal exactly on the noise-free
arm (least squares), cast ``--casts`` times with the arm's noise (the median attempt length of
our learners is 1 to 3 movements; the budget is 10). Its best noisy distance against memory's
closest is the noisy gain an oracle would show. The same with noise-free distances on both
sides (each stored action re-evaluated on the noise-free arm) is the gain measured fairly.
Beside the oracle, the learner's own goal-directed attempt (GoalAttempt, no exploration) on
each goal, from a copy of the same memory, measured both ways.

Run: .venv/bin/python benchmarks/measure_gain_oracle.py --world arm-20 --seeds 0 1 2
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_learners import goals_for, parse_set

from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.goal_reaching import GoalAttempt, probe_scale_for
from sgim_nodes.core.learners import inverse_model_for, make_learner
from sgim_nodes.core.planar_arm import ARMS
from sgim_nodes.core.runner import build_world, run


def oracle_gains(memory, goals: np.ndarray, postures: np.ndarray, noisy, exact,
                 casts: int) -> tuple[float, float, float]:
    """(noisy gain of the oracle, its noise-free gain, share of goals where the noisy gain is
    positive) over the goals, against the memory as it is."""
    noisy_gain, true_gain = [], []
    for goal, posture in zip(goals, postures, strict=True):
        d_mem, i = memory.nearest(goal, 1)
        best = min(float(np.linalg.norm(noisy.execute(posture).outcome - goal))
                   for _ in range(casts))
        noisy_gain.append(float(d_mem[0]) - best)
        mem_true = float(np.linalg.norm(exact.forward(memory.actions[int(i[0])]) - goal))
        true_gain.append(mem_true - float(np.linalg.norm(exact.forward(posture) - goal)))
    g = np.array(noisy_gain)
    return float(g.mean()), float(np.mean(true_gain)), float(np.mean(g > 0)), float(casts)


def attempt_gains(learner, goals: np.ndarray, noisy, exact, seed: int,
                  overrides: dict) -> tuple[float, float, float, float]:
    """The learner's own goal-directed attempt at each goal, each from a copy of its memory
    (``overrides``: LearnerConfig values for the attempt only): (noisy gain, noise-free gain,
    share of goals where the noisy gain is positive, mean movements per attempt)."""
    config = dataclasses.replace(learner.config, explore_gain=0.0, **overrides)
    rng = np.random.default_rng(seed)
    noisy_gain, true_gain, lengths = [], [], []
    for goal in goals:
        memory = copy.deepcopy(learner.memory)
        d_mem, i = memory.nearest(goal, 1)
        inverse = inverse_model_for(memory, config, learner.scale)
        attempt = GoalAttempt(goal, memory, inverse, config,
                              learner.scale, rng, memory.action_dim,
                              probe_scale_for(config, learner.scale, memory.action_dim))
        best_action, best = None, float("inf")
        while not attempt.done:
            action, label = attempt.next_action()
            result = noisy.execute(action)
            memory.add(action, result.outcome, label)
            attempt.observe(action, result)
            if attempt.best_distance < best:
                best, best_action = attempt.best_distance, np.asarray(action, float).copy()
        noisy_gain.append(float(d_mem[0]) - best)
        mem_true = float(np.linalg.norm(exact.forward(learner.memory.actions[int(i[0])]) - goal))
        true_gain.append(mem_true - float(np.linalg.norm(exact.forward(best_action) - goal)))
        lengths.append(attempt.movements)
    g = np.array(noisy_gain)
    return (float(g.mean()), float(np.mean(true_gain)), float(np.mean(g > 0)),
            float(np.mean(lengths)))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--world", choices=sorted(ARMS), default="arm-20")
    p.add_argument("--learner", default="saggriac")
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    p.add_argument("--checkpoints", type=int, nargs="+", default=[500, 1000, 2000, 5000])
    p.add_argument("--casts", type=int, nargs="+", default=[1, 3, 10],
                   help="movements of the oracle's attempt")
    p.add_argument("--attempt-set", action="append", default=[], metavar="NAME=VALUE",
                   help="a LearnerConfig value for our probe attempts only, e.g. "
                        "attempt_patience=10 (repeatable; the learning run keeps the defaults)")
    a = p.parse_args(argv)
    overrides = parse_set(a.attempt_set)
    t0 = time.perf_counter()
    postures, goals = goals_for(a.world, "validation")
    exact = ARMS[a.world].make(0, noise=0.0)
    print(f"{a.world}, {a.learner}, {len(goals)} validation goals, noise "
          f"{ARMS[a.world].make(0).noise}; oracle = the exact posture cast N times, best kept")
    rows: dict[tuple[int, int], list[tuple[float, float, float]]] = {}
    for seed in a.seeds:
        world = build_world(a.world, seed)
        learner = make_learner(a.learner, world.env.action_dim, world.env.outcome_dim, seed,
                               LearnerConfig(), world.scale)
        noisy = ARMS[a.world].make(1000 + seed)
        done = 0
        for checkpoint in a.checkpoints:
            run(learner, world, checkpoint - done, 0, seed, lambda record: None)
            done = checkpoint
            for casts in a.casts:
                rows.setdefault((checkpoint, casts), []).append(
                    oracle_gains(learner.memory, goals, postures, noisy, exact, casts))
            rows.setdefault((checkpoint, 0), []).append(
                attempt_gains(learner, goals, noisy, exact, seed, overrides))
    print(f"attempt settings: {overrides or 'the defaults'}")
    print(f"{'movements':>9s} {'attempt':>18s} {'length':>6s}  noisy gain (positive share)"
          "   noise-free gain")
    for (checkpoint, casts), r in sorted(rows.items()):
        noisy_gain, true_gain, positive, length = np.mean(r, axis=0)
        who = "ours (GoalAttempt)" if casts == 0 else "oracle"
        print(f"{checkpoint:9d} {who:>18s} {length:6.1f}  {noisy_gain:+.4f} ({positive:.2f})"
              f"               {true_gain:+.4f}")
    print(f"({len(a.seeds)} seeds, {time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
