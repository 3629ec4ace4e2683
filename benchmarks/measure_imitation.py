"""How far imitations land from the demonstrated outcome, against imitation_epsilon (issue 11).

An imitation is the demonstrated action plus a random vector of norm below epsilon
(core/imitation.py). For each teaching-set entry and each epsilon, cast ``--casts`` imitations in
the fishing world (with its motor noise) and measure the distance of each landing to the
demonstrated outcome; a cast on land counts as failed and is reported apart. epsilon = 0 is the
world's own noise around the demonstration: the spread any imitation has at least.

Run: PYTHONPATH=sgim_nodes:sim_bridge .venv/bin/python benchmarks/measure_imitation.py
     ... --epsilons 0 0.01 0.02 0.05 0.1 0.2 --casts 20
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "sgim_nodes"), str(REPO / "sim_bridge")]

from sgim_nodes.core.imitation import perturb  # noqa: E402
from sim_bridge import scaling  # noqa: E402
from sim_bridge.data_files import load_teaching_set  # noqa: E402
from sim_bridge.fishing_world import FishingWorld  # noqa: E402


def measure(epsilons: list[float], casts: int, seed: int) -> list[dict]:
    ts = load_teaching_set()
    world = FishingWorld(seed=seed)
    rng = np.random.default_rng(seed)
    rows = []
    for eps in epsilons:
        dists, failed = [], 0
        for action, outcome in zip(ts.actions, ts.outcomes, strict=True):
            for _ in range(casts):
                a = perturb(action, eps, rng) if eps > 0 else np.asarray(action, float)
                r = world.execute(a)
                if r.outcome is None:
                    failed += 1
                else:
                    dists.append(float(np.linalg.norm(r.outcome - outcome)))
        d = np.array(dists)
        rows.append({"epsilon": eps, "median": float(np.median(d)), "mean": float(d.mean()),
                     "p90": float(np.quantile(d, 0.9)), "within_noise": float(
                         np.mean(d <= scaling.OUTCOME_NOISE)),
                     "failed": failed / (failed + len(d))})
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--epsilons", type=float, nargs="+",
                   default=[0.0, 0.01, 0.02, 0.05, 0.1, 0.2])
    p.add_argument("--casts", type=int, default=20, help="imitations per entry and epsilon")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    rows = measure(args.epsilons, args.casts, args.seed)
    print(f"imitation landings against the demonstrated outcome (world noise "
          f"{scaling.OUTCOME_NOISE}), {args.casts} casts per teaching entry and epsilon")
    print(f"{'epsilon':>8} {'median':>8} {'mean':>8} {'p90':>8} {'<=noise':>8} {'on land':>8}")
    for r in rows:
        print(f"{r['epsilon']:8.3f} {r['median']:8.3f} {r['mean']:8.3f} {r['p90']:8.3f} "
              f"{r['within_noise']:8.2f} {r['failed']:8.2f}")
    print(f"({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
