"""Where do a goal babbler's goals and outcomes go on an arm? (issue 10: SAGG-RIAC vs random goals)

Probe points: one reachable point per reachable cell of a 40 x 40 grid over the arm's box
(planar_arm.reach_of, its own seed: neither the benchmark nor the validation goals). Every
``--every`` movements it prints, per learner and seed:
- coverage: distance from each probe to memory's nearest outcome (mean, 90th percentile);
- the learner's noise-free error at the probes (its inverse model, cast without noise), over
  all probes, the edge ones (within 2 cells of never-reachable space) and the inner ones;
- the share of the frame's goals that memory already reached within the success tolerance
  before the attempt ("mastered");
- where the goals of the last frame went: share in reachable space per mode, and how evenly the
  reachable goals spread over the probes (coefficient of variation of goals per probe's cell,
  share of probes with no goal within 2 cells);
- the region tree: the smaller child's share of the goals at each split (mean), leaves and
  the share of mode-1 probability on leaves holding unreachable goals only, reachable only,
  or both.
Nothing here changes the learner.

Run: .venv/bin/python benchmarks/measure_coverage.py --learners random-goals saggriac --seeds 0 1 2
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "sgim_nodes"), str(REPO / "benchmarks")]

from bench_learners import parse_set, reach_map  # noqa: E402

from sgim_nodes.core.config import LearnerConfig  # noqa: E402
from sgim_nodes.core.goal_selection import region_probabilities  # noqa: E402
from sgim_nodes.core.learners import make_learner  # noqa: E402
from sgim_nodes.core.planar_arm import ARMS, reach_of  # noqa: E402
from sgim_nodes.core.runner import build_world  # noqa: E402

PROBE_SEED = 11


def run(world_name: str, learner_name: str, seed: int, movements: int, every: int,
        overrides: dict) -> list[dict]:
    spec = ARMS[world_name]
    probes = reach_of(spec.make(0, noise=0.0), 40, PROBE_SEED).reached_points()[1]
    cell = float(np.max((np.array(spec.box[1]) - np.array(spec.box[0])) / 40))
    reach = reach_map(world_name)
    arm = spec.make(0, noise=0.0)
    world = build_world(world_name, seed)
    learner = make_learner(learner_name, world.env.action_dim, world.env.outcome_dim, seed,
                           LearnerConfig(**overrides), world.scale)
    # probes within 2 cells of never-reachable space: the edge of the reachable set
    centres = (np.stack(np.meshgrid(np.arange(40), np.arange(40), indexing="ij"), -1) + 0.5
               ) / 40 * (reach.high - reach.low) + reach.low
    edge = cKDTree(centres[~reach.reached]).query(probes)[0] < 2 * cell
    tolerance = LearnerConfig(**overrides).distances(world.scale).success_tolerance
    goals: list[tuple[int, int, np.ndarray, float]] = []  # (movement, mode, goal, start)
    original = learner._new_process

    def new_process():
        p = original()
        if hasattr(p, "goal") and type(p).__name__ == "GoalAttempt":
            goals.append((learner.n_movements, learner.last_goal_mode, p.goal.copy(),
                          p.start_distance))
        return p

    learner._new_process = new_process
    splits: list[float] = []  # smaller child's share of the goals, per split
    original_split = learner.tree._split

    def split(leaf):
        original_split(leaf)
        if leaf.children is not None:
            sizes = [len(c.goals) for c in leaf.children]
            splits.append(min(sizes) / sum(sizes))

    learner.tree._split = split
    rows = []
    for i in range(1, movements + 1):
        action, _ = learner.next_action()
        learner.observe(action, world.env.execute(action))
        if i % every:
            continue
        d, _ = cKDTree(learner.memory.outcomes).query(probes)
        err = np.array([np.linalg.norm(arm.forward(learner.inverse(g)) - g) for g in probes])
        frame = [(m, g) for t, m, g, _ in goals if i - every <= t < i]
        starts = np.array([s for t, _, _, s in goals if i - every <= t < i])
        row = {"movement": i, "cover_mean": d.mean(), "cover_p90": np.quantile(d, 0.9),
               "error": err.mean(), "error_p90": np.quantile(err, 0.9), "n_goals": len(frame),
               "error_edge": err[edge].mean(), "error_inner": err[~edge].mean(),
               "goals_mastered": float(np.mean(starts <= tolerance)) if len(starts) else np.nan}
        for mode in (1, 2, 3):
            g = np.array([g for m, g in frame if m == mode])
            row[f"mode{mode}_share"] = len(g) / max(1, len(frame))
            row[f"mode{mode}_reach"] = 1 - reach.share(g) if len(g) else np.nan
        g = np.array([g for _, g in frame])
        if len(g):
            reachable = g[np.array([reach.share(x[None]) == 0.0 for x in g])]
            near = (cKDTree(reachable).query_ball_point(probes, 2 * cell, return_length=True)
                    if len(reachable) else np.zeros(len(probes)))
            row["goals_cv"] = near.std() / max(near.mean(), 1e-9)
            row["probes_no_goal"] = float(np.mean(near == 0))
        leaves = learner.tree.leaves
        probs = region_probabilities(learner.tree.interests(), np.array([r.volume for r in leaves]))
        kinds = np.zeros(3)
        for p, leaf in zip(probs, leaves, strict=True):
            if not leaf.goals:
                continue
            share = reach.share(np.array(leaf.goals))
            kinds[0 if share == 1 else 1 if share == 0 else 2] += p
        row.update(split_min_share=np.mean(splits) if splits else np.nan,
                   leaves=len(leaves), p_unreach_leaf=kinds[0], p_reach_leaf=kinds[1],
                   p_mixed_leaf=kinds[2])
        # attempts per probe over the whole run (where the learner practised)
        rows.append(row)
    # evenness of all outcomes over the reachable set at the end
    n_near = cKDTree(learner.memory.outcomes).query_ball_point(probes, 2 * cell,
                                                              return_length=True)
    rows[-1]["outcomes_cv"] = n_near.std() / n_near.mean()
    rows[-1]["probes_few_outcomes"] = float(np.mean(n_near < 3))
    return rows


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--world", default="arm-20", choices=list(ARMS))
    p.add_argument("--learners", nargs="+", default=["random-goals", "saggriac"])
    p.add_argument("--set2", action="append", default=None, metavar="NAME=VALUE",
                   help="also run saggriac with these overrides")
    p.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    p.add_argument("--movements", type=int, default=3000)
    p.add_argument("--every", type=int, default=500)
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    a = p.parse_args()
    overrides = parse_set(a.set)
    keys = ["cover_mean", "cover_p90", "error", "error_edge", "error_inner", "goals_mastered",
            "error_p90", "mode1_reach", "mode2_reach",
            "mode3_reach", "goals_cv", "probes_no_goal", "split_min_share", "leaves",
            "p_unreach_leaf", "p_reach_leaf", "p_mixed_leaf"]
    jobs = [(name, overrides) for name in a.learners]
    if a.set2:
        jobs.append(("saggriac", {**overrides, **parse_set(a.set2)}))
    for name, over in jobs:
        runs = [run(a.world, name, s, a.movements, a.every, over) for s in a.seeds]
        print(f"=== {a.world} {name} seeds {a.seeds} {over or ''}")
        print("movement " + " ".join(f"{k:>9.9s}" for k in keys))
        for j, row in enumerate(runs[0]):
            vals = [np.nanmean([r[j].get(k, np.nan) for r in runs]) for k in keys]
            print(f"{row['movement']:8d} " + " ".join(f"{v:9.4f}" for v in vals))
        cv = np.mean([r[-1]["outcomes_cv"] for r in runs])
        few = np.mean([r[-1]["probes_few_outcomes"] for r in runs])
        print(f"final outcomes per probe (2 cells): cv {cv:.2f}, "
              f"probes with < 3 outcomes {few:.3f}")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
