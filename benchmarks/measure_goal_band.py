"""Do goals far from reachable space help goal babbling? random-goals restricted to a band.

A diagnostic of issue 10's "SAGG-RIAC better than random goals" (docs/learners.md, 4d): the
interest keeps mode-1 goals out of space no movement reaches, which the issue also asks for.
If goals there are useless, a random-goals learner whose goals are redrawn until they lie
within ``margin`` (box sides) of reachable space should do no worse than unrestricted random
goals; if it does worse, goals beyond the frontier do work that an interest avoiding them
gives up. The band comes from the benchmark's reach map (an oracle no learner has): its 40 x
40 never-reached cells, dilated by the margin. Validation goals, 5000 movements.

Run:  .venv/bin/python benchmarks/measure_goal_band.py                   (arm-20, ~4 min)
      .venv/bin/python benchmarks/measure_goal_band.py --worlds arm-7 --margins 0.05 0.3
      .venv/bin/python benchmarks/measure_goal_band.py --margins 0.05 \
          --set explore_distance_size=0.05
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from scipy import ndimage

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "sgim_nodes"), str(REPO / "benchmarks")]

import bench_learners as bl  # noqa: E402
from learner_probes import ReachMap  # noqa: E402

from sgim_nodes.core.config import LearnerConfig  # noqa: E402
from sgim_nodes.core.learners import make_learner  # noqa: E402
from sgim_nodes.core.planar_arm import ARMS  # noqa: E402
from sgim_nodes.core.runner import build_world, run  # noqa: E402

UNRESTRICTED = float("inf")


def band(reach: ReachMap, margin: float) -> ReachMap:
    """The cells within ``margin`` box sides of a reached cell (as a ReachMap's ``reached``)."""
    if not np.isfinite(margin):
        return ReachMap(reach.low, reach.high, np.ones_like(reach.reached))
    cells = reach.reached.shape[0]
    side = float((reach.high - reach.low)[0])
    distance = ndimage.distance_transform_edt(~reach.reached) * side / cells
    return ReachMap(reach.low, reach.high, distance <= margin)


def one_run(job: tuple[str, float, int, int, dict, int]) -> dict:
    name, margin, seed, movements, overrides, after = job
    allowed = band(bl.REACH[name], margin)  # each worker's map, made once (bl._init)
    world = build_world(name, seed)
    world.goals = bl.goals_for(name, "validation")[1]
    learner = make_learner("random-goals", world.env.action_dim, world.env.outcome_dim, seed,
                           LearnerConfig(**overrides), world.scale)
    if np.isfinite(margin):
        bl.restrict_to_reachable(learner, allowed, after)
    curve = run(learner, world, movements, movements, seed, lambda record: None)
    return {"world": name, "margin": margin, "seed": seed, "final": curve[-1],
            "excluded": allowed.area_share}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--worlds", nargs="+", default=["arm-20"], choices=list(ARMS))
    p.add_argument("--margins", nargs="+", type=float, default=[0.05, 0.15, 0.3],
                   help="band widths in box sides (the unrestricted learner always runs too)")
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--movements", type=int, default=5000)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--after", type=int, default=0, metavar="MOVEMENT",
                   help="restrict goals only from this movement on (uniform before it): "
                   "does late focus pay once the frontier is found?")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a LearnerConfig field for every run (repeatable)")
    a = p.parse_args(argv)
    if a.seeds < 2 or a.movements < 1 or a.jobs < 1 or any(m <= 0 for m in a.margins):
        p.error("--seeds must be >= 2, --movements and --jobs >= 1, every margin > 0")
    if not 0 <= a.after < a.movements:
        p.error("--after must be in [0, --movements)")
    overrides = bl.parse_set(a.set)
    margins = [UNRESTRICTED, *sorted(set(a.margins), reverse=True)]
    jobs = [(w, m, s, a.movements, overrides, a.after) for w in a.worlds for m in margins
            for s in range(a.seeds)]
    print(f"random-goals, {a.seeds} seeds x {a.movements} movements, validation goals, "
          f"overrides: {overrides or 'none'}; goals redrawn until within the margin of "
          f"reachable space{f' from movement {a.after} on' if a.after else ''}")
    start = time.perf_counter()
    with ProcessPoolExecutor(a.jobs, initializer=bl._init, initargs=(a.worlds,)) as pool:
        results = list(pool.map(one_run, jobs))
    for world in a.worlds:
        free = [r["final"] for r in results if r["world"] == world and r["margin"] == UNRESTRICTED]
        print(f"=== {world}")
        for m in margins:
            rows = [r for r in results if r["world"] == world and r["margin"] == m]
            v = [r["final"] for r in rows]
            mean, half = bl.interval(v)
            label = "unrestricted" if m == UNRESTRICTED else f"within {m:.2f}"
            tail = ("" if m == UNRESTRICTED
                    else f"; against unrestricted p = {bl.welch(v, free):.3g}")
            print(f"  {label:13s} excluded area {rows[0]['excluded']:.2f}  "
                  f"error {mean:.4f} +- {half:.4f}{tail}")
    print(f"wall time {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
