"""The learners on analytic arms, with the floor of what is possible (issue 10, item 7).

Worlds with no physics (core/planar_arm.py ARMS), so 10 seeds x 5000 movements of every learner
take minutes: a 7-joint arm whose reachable disc fills most of its box, and a 20-joint arm of
small joint range whose declared goal box is about 4 times its reachable area; both with
Gaussian outcome noise. Learners: random, random-goals, saggriac, sgim-d (its teaching set
built as for the fishing world: 27 reached outcomes from distinct grid cells).

Printed: error curves (mean over seeds every 500 movements), a table of final errors with 95 %
intervals, Welch tests of the comparisons issue 10 asks for, the floor (for each test goal the
best action found by optimising on the noise-free arm, then cast with noise), and probes of the
lower level and the interest (sgim_nodes/experiments/probes.py): gain of goal attempts on
memory, exploration share, real against shuffled interest, and the share of mode-1 goals in
never-reachable space per 500-movement frame against that space's share of the box.

``--goals validation`` evaluates on a second goal set (other points of the same grid cells;
on fishing too, without a floor): parameters are chosen there, and reported on the benchmark
set, never tuned on it.

The published figures come from the pinned experiment experiments/learners.yaml
(``ros_ws/reproduce.sh learners``), which makes the same runs; this script is for comparisons
on the side (other parameters with --set, the validation goals).

Run:  .venv/bin/python benchmarks/bench_learners.py                      (all, ~15 min on 2 cores)
      .venv/bin/python benchmarks/bench_learners.py --seeds 3 --movements 2000 --worlds arm-20
      .venv/bin/python benchmarks/bench_learners.py --set optimiser=nelder-mead --goals validation
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from scipy import stats

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "sgim_nodes"), str(REPO / "sim_bridge")]

from sgim_nodes.core.config import LearnerConfig  # noqa: E402
from sgim_nodes.core.learner_registry import RANDOM, RANDOM_GOALS, SAGGRIAC, SGIM_D  # noqa: E402
from sgim_nodes.core.teaching import DEFAULT_REACHED_RULE, REACHED_RULES  # noqa: E402
from sgim_nodes.experiments.reports.learners import (  # noqa: E402
    COMPARISONS,
    figure,
    frame_means,
)
from sgim_nodes.experiments.runner_jobs import (  # noqa: E402
    FRAME,
    SAME_MEMORY_CASTS,
    WORLDS,
    RunnerJob,
    floor,
    run_job,
)

LEARNERS = (RANDOM, RANDOM_GOALS, SAGGRIAC, SGIM_D)


def run_one(job: RunnerJob) -> dict:
    out = run_job(job)
    out.update(world=job.world, learner=job.learner, seed=job.seed)
    return out


def welch(a: list[float], b: list[float]) -> float:
    if len(a) < 2 or len(b) < 2:
        return float("nan")
    return float(stats.ttest_ind(a, b, equal_var=False).pvalue)


def interval(v: list[float]) -> tuple[float, float]:
    v = np.asarray(v, float)
    if len(v) < 2:
        return float(v.mean()), float("nan")
    return float(v.mean()), float(stats.t.ppf(0.975, len(v) - 1) * v.std(ddof=1)
                                  / np.sqrt(len(v)))


def report(results: list[dict], floors: dict[str, float], movements: int,
           eval_every: int) -> None:
    for name in dict.fromkeys(r["world"] for r in results):
        rows = [r for r in results if r["world"] == name]
        learners = list(dict.fromkeys(r["learner"] for r in rows))
        finals = {lr: [r["final"] for r in rows if r["learner"] == lr] for lr in learners}
        print(f"\n=== {name}: floor {floors[name]:.4f} ===")
        marks = list(range(0, movements + 1, eval_every))
        step = max(1, FRAME // max(eval_every, 1))
        header = "movements".ljust(14) + "".join(f"{m:>8d}" for m in marks[::step])
        print("error curve (mean over seeds)\n" + header)
        for lr in learners:
            curves = np.array([r["curve"] for r in rows if r["learner"] == lr])
            print(lr.ljust(14) + "".join(f"{v:8.4f}" for v in curves.mean(0)[::step]))
        print("\nfinal error: mean +- 95% half-width (n), ratio to floor")
        for lr in learners:
            m, h = interval(finals[lr])
            print(f"  {lr:14s} {m:.4f} +- {h:.4f} (n={len(finals[lr])})  "
                  f"{m / floors[name]:.2f} x floor")
        print("the same final memories, our inverse model against the nearest neighbour "
              f"(noise-free on the arms, {SAME_MEMORY_CASTS} casts per goal on fishing):")
        for lr in learners:
            same = [r["same_memory"] for r in rows if r["learner"] == lr]
            ours, near = (np.array([m[k] for m in same]) for k in ("ours", "nearest"))
            print(f"  {lr:14s} ours {ours.mean():.4f}, nearest {near.mean():.4f}; ours no worse "
                  f"in {int(np.sum(ours <= near))}/{len(ours)} runs (ours - nearest per run: "
                  f"{' '.join(f'{d:+.4f}' for d in ours - near)})")
        demos = [r["n_demonstrations"] for r in rows if r["learner"] == SGIM_D]
        if demos:
            print(f"demonstrations per sgim-d run: {demos}")
        print("Welch tests (two-sided p):")
        for a, b in COMPARISONS:
            if a in finals and b in finals:
                ma, mb = np.mean(finals[a]), np.mean(finals[b])
                print(f"  {a} vs {b}: {ma:.4f} vs {mb:.4f}, p = {welch(finals[a], finals[b]):.3g}")
        print("lower level and interest (mean over seeds):")
        for lr in learners:
            probes = [r["probe"] for r in rows if r["learner"] == lr and "probe" in r]
            if not probes:
                continue
            def avg(key: str, probes: list[dict] = probes) -> float:
                return float(np.nanmean([p[key] for p in probes]))
            shares = frame_means(np.array([p["mode1_unreachable_share"] for p in probes], float))
            print(f"  {lr:14s} goals {avg('n_goals'):.0f}, explore {avg('explore_share'):.2f}, "
                  f"gain on memory {avg('gain_mean'):+.4f} (positive in "
                  f"{avg('gain_positive_share'):.2f}; goals in reachable space "
                  f"{avg('gain_reachable_mean'):+.4f}, elsewhere "
                  f"{avg('gain_unreachable_mean'):+.4f}; no outcome at all "
                  f"{avg('no_outcome_share'):.2f}), start {avg('start_distance_mean'):.4f} "
                  f"-> best {avg('best_distance_mean'):.4f}; interest real "
                  f"{avg('interest_real'):.4f} vs shuffled {avg('interest_shuffled'):.4f}")
            if "true_gain_mean" in probes[0]:
                print(f"  {'':14s} without noise (arms): gain on memory "
                      f"{avg('true_gain_mean'):+.4f} (positive in "
                      f"{avg('true_gain_positive_share'):.2f}; goals in reachable space "
                      f"{avg('true_gain_reachable_mean'):+.4f})")
            if shares is None:  # random-goals: every goal is mode 2
                continue
            print(f"  {'':14s} mode-1 goals in never-reachable space per {FRAME}: "
                  + " ".join("-" if np.isnan(s) else f"{s:.2f}" for s in shares)
                  + f"  (area share {probes[0]['unreachable_area_share']:.2f})")




def parse_set(items: list[str]) -> dict:
    values = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or name not in LearnerConfig.field_names():
            raise SystemExit(f"--set {item!r}: expected NAME=VALUE, NAME a LearnerConfig field")
        try:
            values[name] = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            values[name] = text  # a plain string such as optimiser=nelder-mead
    LearnerConfig(**values)  # refuse bad values before starting the pool
    return values


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--worlds", nargs="+", choices=WORLDS, default=list(WORLDS[:-1]),
                   help="analytic arms by default; 'fishing' runs the pybullet world (slow)")
    p.add_argument("--learners", nargs="+", choices=LEARNERS, default=list(LEARNERS))
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--first-seed", type=int, default=0,
                   help="seeds first-seed .. first-seed + seeds - 1 (more seeds of a "
                   "comparison without running the first ones again)")
    p.add_argument("--movements", type=int, default=5000)
    p.add_argument("--eval-every", type=int, default=250)
    p.add_argument("--goals", choices=("benchmark", "validation"), default="benchmark",
                   help="the benchmark goals, or other points of their cells (choose there)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a LearnerConfig value for every learner (repeatable)")
    p.add_argument("--reached-rule", choices=REACHED_RULES, default=DEFAULT_REACHED_RULE,
                   help="when the teacher counts a teaching goal as reached (core/teaching.py; "
                        f"default {DEFAULT_REACHED_RULE})")
    p.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    p.add_argument("--figure", type=Path, help="write the error curves to this PNG")
    p.add_argument("--json", type=Path, help="write every run's numbers to this file")
    args = p.parse_args(argv)
    if args.seeds < 1 or args.first_seed < 0 or args.movements < 1 or args.jobs < 1:
        p.error("--seeds, --movements and --jobs must be >= 1, --first-seed >= 0")
    overrides = parse_set(args.set)
    t0 = time.perf_counter()
    floors = {}
    for name in args.worlds:
        floors[name], _ = floor(name, args.goals)
    jobs = [RunnerJob(w, lr, s, args.movements, args.eval_every, args.goals,
                      tuple(sorted(overrides.items())), args.reached_rule)
            for w in args.worlds for lr in args.learners
            for s in range(args.first_seed, args.first_seed + args.seeds)]
    print(f"{len(jobs)} runs on {args.jobs} processes, goals: {args.goals}, overrides: "
          f"{overrides or 'none'}, teacher rule: {args.reached_rule}", file=sys.stderr)
    with ProcessPoolExecutor(args.jobs) as pool:
        results = []
        for i, r in enumerate(pool.map(run_one, jobs), 1):
            results.append(r)
            print(f"\r{i}/{len(jobs)} runs", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    report(results, floors, args.movements, args.eval_every)
    print(f"\nwall time {time.perf_counter() - t0:.0f} s")
    if args.figure:
        figure(results, floors, args.eval_every, args.figure)
    if args.json:
        args.json.write_text(json.dumps({"floors": floors, "runs": results,
                                         "overrides": overrides,
                                         "teacher_rule": args.reached_rule}, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
