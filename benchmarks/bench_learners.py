"""The learners on analytic arms, with the floor of what is possible (issue 10, item 7).

Worlds with no physics (core/planar_arm.py ARMS), so 10 seeds x 5000 movements of every learner
take minutes: a 7-joint arm whose reachable disc fills most of its box, and a 20-joint arm of
small joint range whose declared goal box is about 4 times its reachable area; both with
Gaussian outcome noise. Learners: random, random-goals, saggriac, sgim-d (its teaching set
built as for the fishing world: 27 reached outcomes from distinct grid cells).

Printed: error curves (mean over seeds every 500 movements), a table of final errors with 95 %
intervals, Welch tests of the comparisons issue 10 asks for, the floor (for each test goal the
best action found by optimising on the noise-free arm, then cast with noise), and probes of the
lower level and the interest (learner_probes.py): gain of goal attempts on memory, exploration
share, real against shuffled interest, and the share of mode-1 goals in never-reachable space
per 500-movement frame against that space's share of the box.

``--goals validation`` evaluates on a second goal set (other points of the same grid cells;
on fishing too, without a floor): parameters are chosen there, and reported on the benchmark
set, never tuned on it.

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
sys.path[:0] = [str(REPO / "sgim_nodes"), str(REPO / "benchmarks")]

from learner_probes import Probe, ReachMap  # noqa: E402

from sgim_nodes.core.config import LearnerConfig  # noqa: E402
from sgim_nodes.core.learners import GoalBabblingLearner, make_learner  # noqa: E402
from sgim_nodes.core.planar_arm import ARMS, reach_of  # noqa: E402
from sgim_nodes.core.runner import World, build_world, run  # noqa: E402
from sgim_nodes.core.teaching import DEFAULT_REACHED_RULE, REACHED_RULES  # noqa: E402

LEARNERS = ("random", "random-goals", "saggriac", "sgim-d")
ORACLE = "random-goals-reachable"
"""A diagnostic, not a learner of the project: random-goals whose goals are redrawn until they
fall in reachable space (the benchmark's reach map, an oracle no real learner has). It asks
whether goals in unreachable space help or hurt goal babbling."""
WORLDS = (*ARMS, "fishing")
FRAME = 500


GOAL_SEEDS = {"benchmark": 0, "validation": 7}


def goals_for(name: str, kind: str) -> tuple[np.ndarray | None, np.ndarray]:
    """(actions, goals): one reachable point per reachable cell of the arm's benchmark grid
    with the posture that reaches it exactly; ``validation`` draws other points of the cells.
    Fishing: its packaged benchmark goals, or other points of their cells drawn by the same
    tool (make_benchmark_set.validation_goals)."""
    if name == "fishing":
        from sim_bridge.data_files import load_benchmark_goals, load_reachable_map
        from sim_bridge.tools.make_benchmark_set import validation_goals

        if kind == "validation":
            return None, np.asarray(validation_goals(load_reachable_map()), float)
        return None, np.asarray(load_benchmark_goals(), float)
    spec = ARMS[name]
    return reach_of(spec.make(0, noise=0.0), spec.cells, GOAL_SEEDS[kind]).reached_points()


def reach_map(name: str) -> ReachMap:
    """Never-reachable cells of the arm's box on a 40 x 40 grid (planar_arm.reachable_cells:
    random postures, then least squares flooding out from them); for fishing, the cells whose
    centre is on land (no cast ever lands there)."""
    if name == "fishing":
        from sim_bridge.lake import is_water
        from sim_bridge.scaling import outcome_to_world

        centres = (np.stack(np.meshgrid(np.arange(40), np.arange(40), indexing="ij"), -1)
                   + 0.5) / 40 * 2.0 - 1.0
        water = is_water(outcome_to_world(centres.reshape(-1, 2))).reshape(40, 40)
        return ReachMap(np.full(2, -1.0), np.full(2, 1.0), water)
    arm = ARMS[name].make(0, noise=0.0)
    reached = reach_of(arm, 40).reached
    return ReachMap(np.asarray(arm.box[0], float), np.asarray(arm.box[1], float), reached)


def floor(name: str, kind: str, casts: int = 100) -> tuple[float, np.ndarray]:
    """Per goal: the posture that reaches it exactly on the noise-free arm, cast ``casts`` times
    with the arm's noise; the mean distance (for Gaussian noise, about 1.25 sigma). Fishing: the
    floor shipped with its benchmark set (a nearest-action lookup on a dense map of the world,
    cast with noise; sim_bridge.data_files.load_floor), NaN if the data has none or for the
    validation goals (no floor is shipped for them)."""
    if name == "fishing":
        if kind != "benchmark":
            return float("nan"), np.empty(0)
        try:
            from sim_bridge.data_files import load_floor
        except ImportError:
            return float("nan"), np.empty(0)
        per_goal = np.asarray(load_floor().per_goal, float).ravel()
        return float(per_goal.mean()), per_goal
    noisy = ARMS[name].make(123)
    actions, goals = goals_for(name, kind)
    per_goal = np.array([np.mean([np.linalg.norm(noisy.execute(a).outcome - g)
                                  for _ in range(casts)]) for a, g in zip(actions, goals,
                                                                          strict=True)])
    return float(per_goal.mean()), per_goal


SAME_MEMORY_CASTS = 10
"""Casts per goal of the fishing world's same-memory comparison: with 2 (until issue 10's
held-out step check) its verdict flipped on ties, a repeat's difference having a standard
deviation of 0.002-0.005 (docs/learners.md, section 1); 10 halves that or better."""


def same_memory_line(world: World, learner, name: str,
                     casts: int = SAME_MEMORY_CASTS) -> dict[str, float]:
    """The learner's final memory evaluated with its inverse model and with the plain nearest
    neighbour, on the same goals: noise-free on the arms (exact), ``casts`` casts per goal in a
    fresh evaluation world on fishing (the same seed for both models)."""
    from sgim_nodes.core.evaluator import EVALUATION_SEED_OFFSET, Evaluator
    from sgim_nodes.core.inverse_model import InverseModel
    from sgim_nodes.core.learners import inverse_model_for

    models = {"ours": inverse_model_for(learner.memory, learner.config, learner.scale),
              "nearest": InverseModel(learner.memory, "nearest")}
    out = {}
    for label, model in models.items():
        if name in ARMS:
            arm = ARMS[name].make(0, noise=0.0)
            out[label] = float(np.mean([np.linalg.norm(arm.forward(model(g)) - g)
                                        for g in world.goals]))
        else:
            fresh = build_world(name, 10_000 + EVALUATION_SEED_OFFSET)
            ev = Evaluator(fresh.eval_env, world.goals, world.scale.diagonal)
            out[label] = float(np.mean([ev.evaluate(model).mean_distance
                                        for _ in range(casts)]))
    return out


def run_one(job: tuple) -> dict:
    name, learner_name, seed, movements, eval_every, goal_kind, overrides, rule = job
    config = LearnerConfig(**overrides)
    world = build_world(name, seed)
    world.goals = goals_for(name, goal_kind)[1]
    learner = make_learner("random-goals" if learner_name == ORACLE else learner_name,
                           world.env.action_dim, world.env.outcome_dim, seed, config,
                           world.scale)
    if learner_name == ORACLE:
        restrict_to_reachable(learner, REACH[name] if name in REACH else reach_map(name))
    forward = ARMS[name].make(0, noise=0.0).forward if name in ARMS else None
    probe = Probe(learner, forward) if isinstance(learner, GoalBabblingLearner) else None
    start = time.perf_counter()
    curve = run(learner, world, movements, eval_every, seed, lambda record: None,
                teacher_rule=rule)
    out = {"world": name, "learner": learner_name, "seed": seed, "curve": curve,
           "final": curve[-1], "seconds": time.perf_counter() - start,
           "n_demonstrations": learner.memory.labels.count("demonstration"),
           "same_memory": same_memory_line(world, learner, name)}
    if probe is not None:
        out["probe"] = probe.summary(FRAME, movements, REACH[name])
    return out


REACH: dict[str, ReachMap] = {}


def restrict_to_reachable(learner: GoalBabblingLearner, reach: ReachMap,
                          from_movement: int = 0) -> None:
    """Redraw the learner's goals until one falls in reachable space (the ORACLE diagnostic),
    from movement ``from_movement`` on (before it, goals are the learner's own)."""
    sample = learner.selector.sample

    def reachable_sample(rng: np.random.Generator):
        if learner.n_movements < from_movement:
            return sample(rng)
        while True:
            choice = sample(rng)
            if reach.share(np.asarray(choice.goal, float)[None]) == 0.0:
                return choice

    learner.selector.sample = reachable_sample  # type: ignore[method-assign]


def _init(names: list[str]) -> None:
    for n in names:
        REACH[n] = reach_map(n)


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
        demos = [r["n_demonstrations"] for r in rows if r["learner"] == "sgim-d"]
        if demos:
            print(f"demonstrations per sgim-d run: {demos}")
        print("Welch tests (two-sided p):")
        for a, b in (("random-goals", "random"), ("saggriac", "random"), (ORACLE, "random-goals"),
                     ("saggriac", "random-goals"), ("sgim-d", "saggriac")):
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


def frame_means(shares: np.ndarray) -> np.ndarray | None:
    """Mean over runs of each frame's share, NaN where no run drew a mode-1 goal in that
    frame; None when no run drew one at all (a learner without mode 1)."""
    seen = ~np.isnan(shares)
    if not seen.any():
        return None
    counts = seen.sum(0)
    sums = np.where(seen, shares, 0.0).sum(0)
    return np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)


COLOURS = {"random": "tab:gray", "random-goals": "tab:purple", "saggriac": "tab:blue",
           "sgim-d": "tab:red", ORACLE: "tab:olive"}
"""The analysis' colours (analysis/figures.py), so every figure of a learner looks alike."""


def figure(results: list[dict], floors: dict[str, float], eval_every: int, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(r["world"] for r in results))
    fig, axes = plt.subplots(1, len(names), figsize=(5.5 * len(names), 4), squeeze=False)
    for ax, name in zip(axes[0], names, strict=True):
        rows = [r for r in results if r["world"] == name]
        for lr in dict.fromkeys(r["learner"] for r in rows):
            curves = np.array([r["curve"] for r in rows if r["learner"] == lr])
            x = np.arange(curves.shape[1]) * eval_every
            m = curves.mean(0)
            h = (stats.t.ppf(0.975, len(curves) - 1) * curves.std(0, ddof=1)
                 / np.sqrt(len(curves))) if len(curves) > 1 else 0 * m
            colour = COLOURS.get(lr, "tab:gray")
            ax.plot(x, m, label=lr, color=colour)
            ax.fill_between(x, m - h, m + h, alpha=0.2, color=colour)
        ax.axhline(floors[name], color="k", ls="--", lw=1, label="floor")
        ax.set(title=f"{name} ({len(rows) // max(1, len(set(r['learner'] for r in rows)))} "
                     "seeds)", xlabel="movements", ylabel="mean distance to test goals",
               yscale="log")
        ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"figure: {path}")


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
    p.add_argument("--worlds", nargs="+", choices=WORLDS, default=list(ARMS),
                   help="analytic arms by default; 'fishing' runs the pybullet world (slow)")
    p.add_argument("--learners", nargs="+", choices=(*LEARNERS, ORACLE), default=list(LEARNERS),
                   help=f"{ORACLE} is a diagnostic: random goals redrawn until reachable")
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
    p.add_argument("--teacher-rule", choices=REACHED_RULES, default=DEFAULT_REACHED_RULE,
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
    jobs = [(w, lr, s, args.movements, args.eval_every, args.goals, overrides, args.teacher_rule)
            for w in args.worlds for lr in args.learners
            for s in range(args.first_seed, args.first_seed + args.seeds)]
    print(f"{len(jobs)} runs on {args.jobs} processes, goals: {args.goals}, overrides: "
          f"{overrides or 'none'}, teacher rule: {args.teacher_rule}", file=sys.stderr)
    with ProcessPoolExecutor(args.jobs, initializer=_init, initargs=(args.worlds,)) as pool:
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
                                         "teacher_rule": args.teacher_rule}, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
