"""Time one learner through the node graph (recorded) against the single-process runner.

Prints both wall times and CPU times, their ratios against the targets (docs/node_graph.md,
"Processes"), whether the two runs made the same movements, and where the graph's CPU goes:
each process's CPU seconds (sampled from /proc while the run lasts; a process hosting several
nodes is named by its --process), per movement. Run inside the workspace environment:

    source ros_ws/env.sh && python benchmarks/bench_graph_vs_runner.py --movements 5000
    python benchmarks/bench_graph_vs_runner.py --movements 5000 --separate   # a process per node
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from sgim_nodes.core.learner_registry import SGIM_D

REPO = Path(__file__).resolve().parent.parent


TICK = os.sysconf("SC_CLK_TCK")
WALL_TARGET, CPU_TARGET = 1.15, 1.3  # graph against runner, one run (docs/node_graph.md)


def node_cpu(pid: int) -> tuple[str, float] | None:
    """(node name, CPU seconds so far) of a node process of the run, from /proc."""
    try:
        argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    exe = next((a.decode() for a in argv if b"/lib/" in a), "")
    name = exe.rsplit("/", 1)[-1] or "?"
    if name == "composed" and b"--process" in argv:  # a process hosting several nodes
        name = argv[argv.index(b"--process") + 1].decode()
    return name, (int(fields[11]) + int(fields[12])) / TICK


class CpuSampler(threading.Thread):
    """The largest CPU time seen for each node process of the run, until stopped: a process's
    CPU time only grows, and the last sample before it exits is close to its total. The
    samples are also kept in time (wall clock), to tell the steady state from start-up."""

    def __init__(self, run_dir: Path, period: float = 0.5) -> None:
        super().__init__(daemon=True)
        self.run_dir, self.period = run_dir, period
        self.seen: dict[int, tuple[str, float]] = {}
        self.series: list[tuple[float, dict[int, tuple[str, float]]]] = []
        self.stopping = threading.Event()

    def run(self) -> None:
        from sgim_nodes.graph.processes import run_node_pids

        while not self.stopping.wait(self.period):
            for pid in run_node_pids(self.run_dir):
                sample = node_cpu(pid)
                if sample is not None:
                    self.seen[pid] = sample
            self.series.append((time.time(), dict(self.seen)))

    def between(self, start: float, end: float) -> dict[str, float]:
        """CPU seconds each node used between two wall-clock times (the samples nearest
        inside them)."""
        inside = [(t, seen) for t, seen in self.series if start <= t <= end]
        if len(inside) < 2:
            return {}
        (_, first), (_, last) = inside[0], inside[-1]
        out: dict[str, float] = {}
        for pid, (name, cpu) in last.items():
            out[name] = out.get(name, 0.0) + cpu - first.get(pid, (name, 0.0))[1]
        return dict(sorted(out.items(), key=lambda kv: -kv[1]))

    def per_node(self) -> dict[str, float]:
        out: dict[str, float] = {}
        for name, cpu in self.seen.values():
            out[name] = out.get(name, 0.0) + cpu
        return dict(sorted(out.items(), key=lambda kv: -kv[1]))


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def critical_path(run, start: int, end: int) -> str:
    """Median wall times between records of movements start..end (bag stamps): from one
    movement to the next of the same goal, to the first of the next goal, and from a goal's
    previous movement to the goal generator's answer (what a goal waits for)."""
    moves = [m for m in run.movements if start <= m.index <= end]
    same, new = [], []
    for a, b in itertools.pairwise(moves):
        if a.goal_index and b.goal_index:
            (same if a.goal_index == b.goal_index else new).append(b.stamp_ns - a.stamp_ns)
    stamp = {m.index: m.stamp_ns for m in moves}
    chosen = [g.stamp_ns - stamp[g.movement_index] for g in run.goals
              if g.movement_index in stamp]

    def median(ns: list[int]) -> str:
        return f"{np.median(ns) * 1e-6:.1f} ms" if ns else "-"

    return (f"wall time between movements of one goal {median(same)}, between two goals "
            f"{median(new)}; a goal chosen {median(chosen)} after the movement before it")


EXECUTOR = "rclpy/executors.py"
"""rclpy's Python executor: its wait-set rebuild at every wake-up is what the nodes on the
SingleThreadedExecutor (sgim_ros/executors.py) pay per message."""


def profile_shares(folder: Path) -> list[str]:
    """Per node profile: its thread's CPU, the share inside rclpy's Python executor (the
    wait set it rebuilds at every wake-up) and the share in pybullet's calls (the physics);
    the rest is the node's own work and the messages' conversion and middleware calls."""
    import pstats

    lines = []
    for path in sorted(folder.glob("*.prof")):
        stats = pstats.Stats(str(path)).stats  # type: ignore[attr-defined]
        total = sum(own for _, _, own, _, _ in stats.values())
        executor = sum(cum for (file, _, func), (_, _, _, cum, _) in stats.items()
                       if file.endswith(EXECUTOR) and func == "_wait_for_ready_callbacks")
        physics = sum(own for (file, _, func), (_, _, own, _, _) in stats.items()
                      if file == "~" and "pybullet" in func)
        shares = [f"{100 * part / total:3.0f} %" if total else "  - "
                  for part in (executor, physics, total - executor - physics)]
        lines.append(f"{path.stem:20s} {total:6.2f} s: rclpy executor {shares[0]}, "
                     f"physics {shares[1]}, the rest {shares[2]}")
    return lines


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--learner", default=SGIM_D)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--movements", type=int, default=5000)
    p.add_argument("--eval-every", type=int, default=250)
    p.add_argument("--graph-only", action="store_true",
                   help="skip the runner: the graph's time and CPU only (to compare changes)")
    p.add_argument("--profile", action="store_true",
                   help="profile every node with cProfile (sgim_ros/entry.py, SGIM_PROFILE): "
                        "<run>/logs/profile/<node>.prof and .prof.txt; slows the graph")
    p.add_argument("--separate", action="store_true",
                   help="a process per node (run_experiment.sh --separate)")
    p.add_argument("--compose", action="append", default=[], metavar="NAME=NODE,NODE,...",
                   help="group nodes into processes otherwise (run_experiment.sh --compose)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="a node parameter for the graph run (run_experiment.sh --param), e.g. "
                        "goals_per_job=1 to time one reach_goal job per goal")
    args = p.parse_args()
    out = Path(tempfile.mkdtemp(prefix="bench-graph-"))
    common = ["--seed", str(args.seed), "--movements", str(args.movements), "--eval-every",
              str(args.eval_every)]

    start, cpu = time.perf_counter(), children_cpu()
    if not args.graph_only:
        subprocess.run([sys.executable, "-m", "sgim_nodes.core.runner", "--learner",
                        args.learner,
                        "--env", "fishing", "--output", str(out / "runner.jsonl"), "--quiet",
                        *common], check=True)
    runner_s, runner_cpu = time.perf_counter() - start, children_cpu() - cpu

    sampler = CpuSampler(out / "graph")
    sampler.start()
    start = time.perf_counter()
    env = dict(os.environ)
    if args.profile:
        env["SGIM_PROFILE"] = str(out / "graph" / "logs" / "profile")
    subprocess.run([str(REPO / "ros_ws" / "run_experiment.sh"), args.learner, *common,
                    "--runs-dir", str(out), "--name", "graph", "--quiet",
                    *(arg for item in args.param for arg in ("--param", item)),
                    *(["--separate"] if args.separate else []),
                    *(arg for item in args.compose for arg in ("--compose", item))], check=True,
                   env=env)
    graph_s = time.perf_counter() - start
    sampler.stopping.set()
    sampler.join()

    from sgim_nodes.bag.reader import load_run

    run = load_run(out / "graph" / "bag")
    print(f"learner {args.learner}, seed {args.seed}, {args.movements} movements, "
          f"evaluation every {args.eval_every}"
          + "".join(f", {item}" for item in args.param)
          + (", a process per node" if args.separate else "")
          + "".join(f", process {item}" for item in args.compose))
    if not args.graph_only:
        records = [json.loads(line)
                   for line in (out / "runner.jsonl").read_text().splitlines()]
        moves = [r for r in records if r["type"] == "movement"]
        same = len(moves) == len(run.movements) and all(
            np.array_equal(m.action, np.asarray(r["action"]))
            for m, r in zip(run.movements, moves, strict=True))
        print(f"single-process runner: {runner_s:7.1f} s")
    print(f"node graph, recorded:  {graph_s:7.1f} s (start-up and shutdown included)")
    if not args.graph_only:
        print(f"ratio graph / runner:  {graph_s / runner_s:7.2f}  (target <= {WALL_TARGET})")
        print(f"same movements:        {same}")
    per_node = sampler.per_node()
    n = max(args.movements, 1)
    runner = (f"runner {runner_cpu:.1f} s ({1000 * runner_cpu / n:.1f} ms per movement); "
              if not args.graph_only else "")
    print(f"CPU: {runner}graph nodes {sum(per_node.values()):.1f} s "
          f"({1000 * sum(per_node.values()) / n:.1f} ms per movement):")
    for name, cpu in per_node.items():
        print(f"  {name:20s} {cpu:7.1f} s  {1000 * cpu / n:6.2f} ms per movement")
    if not args.graph_only and runner_cpu > 0:
        print(f"CPU ratio graph / runner: {sum(per_node.values()) / runner_cpu:.2f}  (target <= "
              f"{CPU_TARGET})")
    # The steady state: from the movement at 10 % of the run to the one at 90 %, without the
    # nodes' start-up (imports, discovery) and shutdown.
    stamps = [m.stamp_ns * 1e-9 for m in run.movements]
    if len(stamps) >= 20:
        a, b = len(stamps) // 10, len(stamps) * 9 // 10
        window = sampler.between(stamps[a], stamps[b])
        inside = [t for t, _ in sampler.series if stamps[a] <= t <= stamps[b]]
        if window and len(inside) >= 2:
            moved = sum(1 for s in stamps if inside[0] <= s <= inside[-1])
            span = inside[-1] - inside[0]
            print(f"steady state (movements {a + 1}-{b + 1}): {moved} movements in "
                  f"{span:.1f} s, {1000 * span / max(moved, 1):.1f} ms per movement; graph "
                  f"nodes {1000 * sum(window.values()) / max(moved, 1):.1f} ms CPU per "
                  "movement:")
            for name, cpu in window.items():
                print(f"  {name:20s} {1000 * cpu / max(moved, 1):6.2f} ms per movement")
        print(f"critical path (medians, movements {a + 1}-{b + 1}): "
              f"{critical_path(run, a + 1, b + 1)}")
    if args.profile:
        folder = out / "graph" / "logs" / "profile"
        print("where each node's spinning thread spends its CPU (cProfile on thread CPU; "
              "profiling inflates Python's share):")
        for line in profile_shares(folder):
            print(f"  {line}")
        print(f"profiles: {folder}")
    print(f"outputs in {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
