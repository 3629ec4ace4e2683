"""Time one learner through the node graph (recorded) against the single-process runner.

Prints both wall times, their ratio (target: graph <= 1.5 x runner) and whether the two runs
made the same movements. Run inside the workspace environment:

    source ros_ws/env.sh && python benchmarks/bench_graph_vs_runner.py --movements 5000
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--learner", default="sgim-d")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--movements", type=int, default=5000)
    p.add_argument("--eval-every", type=int, default=250)
    args = p.parse_args()
    out = Path(tempfile.mkdtemp(prefix="bench-graph-"))
    common = ["--seed", str(args.seed), "--movements", str(args.movements), "--eval-every",
              str(args.eval_every)]

    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "sgim_nodes.core.runner", "--learner", args.learner,
                    "--env", "fishing", "--output", str(out / "runner.jsonl"), "--quiet",
                    *common], check=True)
    runner_s = time.perf_counter() - start

    start = time.perf_counter()
    subprocess.run([str(REPO / "ros_ws" / "run_experiment.sh"), args.learner, *common,
                    "--runs-dir", str(out), "--name", "graph", "--quiet"], check=True)
    graph_s = time.perf_counter() - start

    from sgim_nodes.bag.reader import load_run

    run = load_run(out / "graph" / "bag")
    records = [json.loads(line) for line in (out / "runner.jsonl").read_text().splitlines()]
    moves = [r for r in records if r["type"] == "movement"]
    same = len(moves) == len(run.movements) and all(
        np.array_equal(m.action, np.asarray(r["action"]))
        for m, r in zip(run.movements, moves, strict=True))
    print(f"learner {args.learner}, seed {args.seed}, {args.movements} movements, "
          f"evaluation every {args.eval_every}")
    print(f"single-process runner: {runner_s:7.1f} s")
    print(f"node graph, recorded:  {graph_s:7.1f} s (start-up and shutdown included)")
    print(f"ratio graph / runner:  {graph_s / runner_s:7.2f}  (target <= 1.5)")
    print(f"same movements:        {same}")
    print(f"outputs in {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
