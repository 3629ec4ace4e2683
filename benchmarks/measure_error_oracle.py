"""Could any goal choice beat random goals on an arm? Goals where the learner errs most, by oracle.

A diagnostic of issue 10's "SAGG-RIAC better than random goals on the 20-joint arm"
(docs/learners.md, 4e). SAGG-RIAC can only beat random goals by placing its goals better. This
gives random-goals the best placement an interest could hope to find, from an oracle no learner
has: from movement ``--after`` on, every ``--every`` movements, the learner's noise-free error
is measured at the centre of each reachable cell of the benchmark's 40 x 40 reach map, and
goals are drawn in those cells with a probability proportional to that error to the power
``--power`` (1: where it errs most, 0: uniform over reachable cells), uniformly inside the
cell. Before ``--after``, goals are the
learner's own (uniform in the box: the frontier-pushing that measure_goal_band.py showed is
needed early). If even this oracle does no better than random goals, goal placement is not
what stands between SAGG-RIAC and a lower error on that arm: the lower level is.

Validation goals, 5000 movements; the oracle's probe points are neither validation nor
benchmark goals (centres of the reach map's cells, a finer grid than the benchmark's).

Run:  .venv/bin/python benchmarks/measure_error_oracle.py                     (arm-20, ~6 min)
      .venv/bin/python benchmarks/measure_error_oracle.py --after 1000 --power 2
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from scipy import stats

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "sgim_nodes"), str(REPO / "benchmarks")]

import bench_learners as bl  # noqa: E402
from learner_probes import ReachMap  # noqa: E402

from sgim_nodes.core.config import LearnerConfig  # noqa: E402
from sgim_nodes.core.goal_selection import GoalChoice  # noqa: E402
from sgim_nodes.core.learners import GoalBabblingLearner, make_learner  # noqa: E402
from sgim_nodes.core.planar_arm import ARMS  # noqa: E402
from sgim_nodes.core.runner import build_world, run  # noqa: E402

UNIFORM = "random-goals"
ORACLE = "error-oracle"


def probe_cells(reach: ReachMap) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(centres, lows, highs) of the reached cells of the map."""
    n = np.array(reach.reached.shape)
    width = (reach.high - reach.low) / n
    ij = np.argwhere(reach.reached)
    lows = reach.low + ij * width
    return lows + 0.5 * width, lows, lows + width


class ErrorOracle:
    """Replaces the learner's goal sampler from ``after`` on: cells drawn by error**power."""

    def __init__(self, learner: GoalBabblingLearner, forward, reach: ReachMap, after: int,
                 every: int, power: float) -> None:
        self.learner, self.forward = learner, forward
        self.centres, self.lows, self.highs = probe_cells(reach)
        self.after, self.every, self.power = after, every, power
        self.own = learner.selector.sample
        self.weights: np.ndarray | None = None
        self.measured_at = -1
        self.errors: list[float] = []  # mean probe error at each measurement
        learner.selector.sample = self.sample  # type: ignore[method-assign]

    def _measure(self) -> None:
        actions = np.array([self.learner.inverse(c) for c in self.centres])
        err = np.linalg.norm(self.forward(actions) - self.centres, axis=1)
        self.errors.append(float(err.mean()))
        w = err**self.power
        self.weights = w / w.sum() if w.sum() > 0 else np.full(len(w), 1.0 / len(w))
        self.measured_at = self.learner.n_movements

    def sample(self, rng: np.random.Generator) -> GoalChoice:
        n = self.learner.n_movements
        if n < self.after:
            return self.own(rng)
        if self.weights is None or n - self.measured_at >= self.every:
            self._measure()
        i = int(rng.choice(len(self.weights), p=self.weights))
        return GoalChoice(rng.uniform(self.lows[i], self.highs[i]), 1, i)


def one_run(job: tuple[str, str, int, int, dict, int, int, float]) -> dict:
    name, kind, seed, movements, overrides, after, every, power = job
    world = build_world(name, seed)
    world.goals = bl.goals_for(name, "validation")[1]
    learner = make_learner("random-goals", world.env.action_dim, world.env.outcome_dim, seed,
                           LearnerConfig(**overrides), world.scale)
    oracle = None
    if kind == ORACLE:
        oracle = ErrorOracle(learner, ARMS[name].make(0, noise=0.0).forward, bl.REACH[name],
                             after, every, power)
    curve = run(learner, world, movements, movements, seed, lambda record: None)
    return {"world": name, "kind": kind, "seed": seed, "final": curve[-1],
            "probe_errors": oracle.errors if oracle else []}


def paired(rows: dict[str, list[dict]]) -> str:
    """Both learners are the same run until ``--after`` (same seed, same streams): the
    per-seed difference of their final errors, and its paired t-test."""
    by_seed = {k: {r["seed"]: r["final"] for r in v} for k, v in rows.items()}
    seeds = sorted(set(by_seed[UNIFORM]) & set(by_seed[ORACLE]))
    diff = np.array([by_seed[ORACLE][s] - by_seed[UNIFORM][s] for s in seeds])
    p = stats.ttest_rel([by_seed[ORACLE][s] for s in seeds],
                        [by_seed[UNIFORM][s] for s in seeds]).pvalue if len(seeds) > 1 else np.nan
    return (f"paired by seed: oracle - random-goals {diff.mean():+.4f} (better in "
            f"{int((diff < 0).sum())}/{len(diff)}), paired t-test p = {p:.3g}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--worlds", nargs="+", default=["arm-20"], choices=list(ARMS))
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--first-seed", type=int, default=0,
                   help="seeds first-seed .. first-seed + seeds - 1 (more seeds of a comparison)")
    p.add_argument("--movements", type=int, default=5000)
    p.add_argument("--after", type=int, default=2500, metavar="MOVEMENT",
                   help="the oracle chooses goals from this movement on (uniform before)")
    p.add_argument("--every", type=int, default=250, metavar="MOVEMENTS",
                   help="the learner's error at the probe cells is measured again this often")
    p.add_argument("--power", type=float, default=1.0,
                   help="cells drawn with probability proportional to error**power (>= 0)")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a LearnerConfig field for every run (repeatable)")
    a = p.parse_args(argv)
    if a.seeds < 2 or a.movements < 1 or a.jobs < 1 or a.every < 1 or a.first_seed < 0:
        p.error("--seeds must be >= 2, --movements, --every and --jobs >= 1, --first-seed >= 0")
    if not 0 <= a.after < a.movements:
        p.error("--after must be in [0, --movements)")
    if not (a.power >= 0 and np.isfinite(a.power)):
        p.error("--power must be a finite number >= 0")
    overrides = bl.parse_set(a.set)
    jobs = [(w, k, s, a.movements, overrides, a.after, a.every, a.power)
            for w in a.worlds for k in (UNIFORM, ORACLE)
            for s in range(a.first_seed, a.first_seed + a.seeds)]
    print(f"random-goals against goals drawn by the learner's own error (oracle) from movement "
          f"{a.after} on, every {a.every}, power {a.power:g}; seeds {a.first_seed}-"
          f"{a.first_seed + a.seeds - 1} x {a.movements} "
          f"movements, validation goals, overrides: {overrides or 'none'}")
    start = time.perf_counter()
    with ProcessPoolExecutor(a.jobs, initializer=bl._init, initargs=(a.worlds,)) as pool:
        results = list(pool.map(one_run, jobs))
    for world in a.worlds:
        rows = {k: [r for r in results if r["world"] == world and r["kind"] == k]
                for k in (UNIFORM, ORACLE)}
        finals = {k: [r["final"] for r in v] for k, v in rows.items()}
        print(f"=== {world}")
        for k in (UNIFORM, ORACLE):
            mean, half = bl.interval(finals[k])
            print(f"  {k:13s} error {mean:.4f} +- {half:.4f}  per seed "
                  + " ".join(f"{v:.4f}" for v in finals[k]))
        curves = np.array([r["probe_errors"] for r in rows[ORACLE]])
        print("  oracle's probe-cell error (noise-free, mean over seeds) at each measurement: "
              + " ".join(f"{v:.4f}" for v in curves.mean(axis=0)))
        print(f"  oracle against random-goals: Welch p = "
              f"{bl.welch(finals[ORACLE], finals[UNIFORM]):.3g}; " + paired(rows))
    print(f"wall time {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
