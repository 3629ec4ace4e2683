"""How close a study comes to the physics it cannot avoid: a small study through the graph, two
runs side by side and without the markers node (as run_study.sh makes them), and the same study
made by the single-process runner; the graph/runner wall ratio against its target
(docs/node_graph.md, "Processes").

Printed, for each: the wall time, the CPU of each node (the graph) or of the runners, the casts
made (the learner's movements, and the evaluator's and the teacher's casts that were not kept
from before: core/repeatable_casts.py), the physics CPU (those casts times the CPU one cast
costs, measured in this same invocation, before and after the runs) and the efficiency =
physics CPU / (2 cores x wall). The runner's efficiency is the bound the graph's can reach: it
does the same learning with no messaging at all.

    source ros_ws/env.sh && python benchmarks/bench_study.py
    source ros_ws/env.sh && python benchmarks/bench_study.py --seeds 1 --movements 500
    source ros_ws/env.sh && python benchmarks/bench_study.py --separate   # a process per node

`--made DIR` makes no run: it gives the same figures for the graph runs of an experiment made
already (say runs/experiments/study, by `ros_ws/reproduce.sh study`), from their logs' cast
counts and their metadata's start and end, with one cast's CPU measured now. Its wall time
is the time at least one of its runs was running (so a pause between two sittings of a resumed
experiment does not count), and its cores those of this machine.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benchmarks"))

from bench_graph_vs_runner import node_cpu  # noqa: E402

from sgim_nodes.core.learner_registry import DEMO_ONLY, RANDOM, SAGGRIAC, SGIM_D  # noqa: E402
from sgim_nodes.graph.processes import node_log  # noqa: E402

STUDY_WALL_TARGET = 1.25  # graph against runner, same runs, same parallelism

RUN = REPO / "ros_ws" / "run_experiment.sh"
CASTS = re.compile(r"casts made (\d+), kept (\d+)")


def cast_cost(casts: int = 60, seed: int = 5) -> float:
    """CPU seconds of one cast of a random action in the default world (this process)."""
    from sim_bridge.fishing_world import FishingWorld

    rng = np.random.default_rng(seed)
    with FishingWorld(seed=seed) as world:
        actions = rng.uniform(-1, 1, (casts, world.action_dim))
        start = time.process_time()
        for action in actions:
            world.execute(action)
        return (time.process_time() - start) / casts


class Sampler(threading.Thread):
    """Each node process's largest CPU time seen, over every run folder of the study."""

    def __init__(self, runs: Path) -> None:
        super().__init__(daemon=True)
        self.runs, self.seen, self.stopping = runs, {}, threading.Event()

    def run(self) -> None:
        from sgim_nodes.graph.processes import run_node_pids

        while not self.stopping.wait(0.5):
            for run_dir in self.runs.iterdir() if self.runs.is_dir() else []:
                for pid in run_node_pids(run_dir):
                    sample = node_cpu(pid)
                    if sample is not None:
                        self.seen[pid] = sample

    def per_node(self) -> dict[str, float]:
        out: dict[str, float] = {}
        for name, cpu in self.seen.values():
            out[name] = out.get(name, 0.0) + cpu
        return dict(sorted(out.items(), key=lambda kv: -kv[1]))


def made_casts(run_dir: Path, movements: int) -> int:
    """The casts a graph run made: its movements, and the evaluator's and teacher's (their
    logs' last counts)."""
    total = movements
    for node in ("evaluator", "teacher"):
        log = node_log(run_dir / "logs", node)
        found = CASTS.findall(log.read_text(errors="replace")) if log.exists() else []
        if found:
            total += int(found[-1][0])
    return total


def busy_seconds(spans: list[tuple[float, float]]) -> float:
    """The length of the union of (start, end) spans: the wall time something was running."""
    total, reach = 0.0, float("-inf")
    for start, end in sorted(spans):
        if end > reach:
            total += end - max(start, reach)
            reach = end
    return total


def made_study(runs: Path, cores: int) -> int:
    """--made: the casts, wall time and efficiency of an experiment's graph runs, made already."""
    from datetime import datetime

    import yaml

    spans, casts, folders = [], 0, []
    for meta_path in sorted(runs.glob("*/metadata.yaml")):
        meta = yaml.safe_load(meta_path.read_text())
        if meta.get("outcome") != "finished" or not meta.get("started") or not meta.get("ended"):
            continue
        folders.append(meta_path.parent.name)
        spans.append((datetime.fromisoformat(meta["started"]).timestamp(),
                      datetime.fromisoformat(meta["ended"]).timestamp()))
        casts += made_casts(meta_path.parent, int(meta.get("movements_done", 0)))
    if not folders:
        raise SystemExit(f"no finished graph run (metadata.yaml, outcome finished) in {runs}")
    cost = cast_cost()
    wall = busy_seconds(spans)
    physics = casts * cost
    run_time = sum(end - start for start, end in spans)
    print(f"{len(folders)} finished runs in {runs}; one cast {1000 * cost:.2f} ms of CPU "
          "(measured now)")
    print(f"wall {wall / 3600:.2f} h (some run running), run time {run_time / 3600:.2f} h "
          f"({run_time / wall:.2f} runs at a time), casts {casts} ({casts / wall:.1f}/s), "
          f"physics {physics / 3600:.2f} h, efficiency {physics / (cores * wall):.2f} on "
          f"{cores} cores")
    return 0


def run_side_by_side(commands: list[list[str]], parallel: int) -> float:
    """Run the commands, `parallel` at a time; the wall time."""
    start = time.perf_counter()
    pending, running = list(commands), []
    while pending or running:
        while pending and len(running) < parallel:
            running.append(subprocess.Popen(pending.pop(0), stdout=subprocess.DEVNULL,
                                            stderr=subprocess.STDOUT))
        for child in list(running):
            if child.poll() is not None:
                if child.returncode != 0:
                    raise SystemExit(f"a run failed (exit {child.returncode}): {child.args}")
                running.remove(child)
        time.sleep(0.2)
    return time.perf_counter() - start


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def runner_study(args: argparse.Namespace, out: Path) -> dict:
    """The same runs by the single-process runner, the casts counted inside it."""
    jobs = [[sys.executable, str(Path(__file__).resolve()), "--one-runner", learner,
             str(seed), str(args.movements), str(out / f"{learner}-{seed}.json")]
            for learner in args.learners for seed in range(args.seeds)]
    cpu = children_cpu()
    wall = run_side_by_side(jobs, args.parallel)
    casts = sum(json.loads(p.read_text())["casts"] for p in out.glob("*.json"))
    return {"wall": wall, "cpu": children_cpu() - cpu, "casts": casts}


def one_runner(learner: str, seed: int, movements: int, path: Path) -> None:
    """One runner run, writing the casts it made (its movements and kept-casts counters)."""
    from sgim_nodes.core import repeatable_casts
    from sgim_nodes.core.learner_registry import make_learner
    from sgim_nodes.core.runner import build_world, run

    made = []
    original = repeatable_casts.RepeatableCasts.__init__

    def keep(self, *a, **k) -> None:
        original(self, *a, **k)
        made.append(self)

    repeatable_casts.RepeatableCasts.__init__ = keep
    world = build_world("fishing", seed)
    learner_ = make_learner(learner, world.env.action_dim, world.env.outcome_dim, seed,
                            scale=world.scale)
    run(learner_, world, movements, 250, seed, lambda record: None)
    path.write_text(json.dumps({"casts": movements + sum(c.made for c in made)}))


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--one-runner":
        one_runner(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), Path(sys.argv[5]))
        return 0
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--learners", nargs="+", default=[SGIM_D, SAGGRIAC, DEMO_ONLY,
                                                     RANDOM])
    p.add_argument("--seeds", type=int, default=2)
    p.add_argument("--movements", type=int, default=2000)
    p.add_argument("--parallel", type=int, default=2, help="runs side by side (the cores)")
    p.add_argument("--graph-only", action="store_true")
    p.add_argument("--separate", action="store_true",
                   help="a process per node (run_experiment.sh --separate)")
    p.add_argument("--compose", action="append", default=[], metavar="NAME=NODE,NODE,...",
                   help="group nodes into processes otherwise (run_experiment.sh --compose)")
    p.add_argument("--made", type=Path, metavar="DIR",
                   help="make no run: the figures of the graph runs in DIR, made already")
    args = p.parse_args()
    if args.made is not None:
        if not args.made.is_dir():
            p.error(f"--made: no folder {args.made}")
        return made_study(args.made, os.cpu_count() or 1)
    if args.seeds < 1 or args.movements < 1 or args.parallel < 1:
        p.error("--seeds, --movements and --parallel must be >= 1")
    out = Path(tempfile.mkdtemp(prefix="bench-study-"))
    cost_before = cast_cost()
    runs = out / "graph"
    runs.mkdir()
    commands = [[str(RUN), learner, "--seed", str(seed), "--movements", str(args.movements),
                 "--runs-dir", str(runs), "--name", f"{learner}-seed{seed}", "--quiet",
                 "--no-markers", *(["--separate"] if args.separate else []),
                 *(a for item in args.compose for a in ("--compose", item))]
                for learner in args.learners for seed in range(args.seeds)]
    sampler = Sampler(runs)
    sampler.start()
    wall = run_side_by_side(commands, args.parallel)
    sampler.stopping.set()
    sampler.join()
    runner = None if args.graph_only else runner_study(args, out)
    cost = (cost_before + cast_cost()) / 2
    casts = sum(made_casts(run_dir, args.movements) for run_dir in runs.iterdir())
    per_node = sampler.per_node()
    cores = args.parallel
    layout = ("a process per node" if args.separate else
              ", ".join(args.compose) if args.compose else "the default processes")
    print(f"{len(commands)} runs ({', '.join(args.learners)} x {args.seeds} seeds x "
          f"{args.movements} movements), {cores} side by side, {layout}; one cast "
          f"{1000 * cost:.2f} ms of CPU (before {1000 * cost_before:.2f})")
    print(f"graph: wall {wall:.1f} s, nodes' CPU {sum(per_node.values()):.1f} s, casts {casts} "
          f"({casts / wall:.1f}/s), physics {casts * cost:.1f} s, efficiency "
          f"{casts * cost / (cores * wall):.2f}")
    for name, cpu in per_node.items():
        print(f"  {name:20s} {cpu:7.1f} s")
    if runner is not None:
        physics = runner["casts"] * cost
        print(f"runner: wall {runner['wall']:.1f} s, CPU {runner['cpu']:.1f} s, casts "
              f"{runner['casts']}, physics {physics:.1f} s, efficiency "
              f"{physics / (cores * runner['wall']):.2f} (the graph's bound); graph / runner: "
              f"wall {wall / runner['wall']:.2f} (target <= {STUDY_WALL_TARGET}), CPU "
              f"{sum(per_node.values()) / runner['cpu']:.2f}")
    print(f"outputs in {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
