"""The web teacher's cost to a run, and the page's responsiveness, in a real headless browser.

Runs the same SGIM-D run (same seed, no demonstration: the same movements) with the web
teacher, alternately without a page and with the page open in headless Chromium, and prints
for each: the arbiter's run time (from its start to its last movement and final evaluation,
as its log says; the nodes' start-up is not the page's cost), the CPU time of the run's
processes (every node, from wait4) and of the browser, and the machine's load. Then the
medians and the page's overhead (target: under 5 %), in run time and in CPU time: on a
machine shared with other jobs the run time swings by tens of percent from run to run, while
CPU time (what the page adds to the machine's work) barely depends on the neighbours. For
the runs with a page it prints how the page kept up: updates per second (target >= 2), the
mean and longest time to apply one update, and updates over 50 ms.

    source ros_ws/env.sh
    python benchmarks/bench_web_teacher.py --movements 1000 --repeats 3
    python benchmarks/bench_web_teacher.py --movements 5000 --repeats 1 --page-only
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from sgim_nodes.core.learner_registry import SGIM_D
from sgim_nodes.graph.processes import node_log

REPO = Path(__file__).resolve().parent.parent
RUN = REPO / "ros_ws" / "run_experiment.sh"
FINISHED = re.compile(r"run finished: (\d+) movements in ([0-9.]+) s")


def one_run(out: Path, name: str, movements: int, seed: int, page: bool) -> dict:
    # --web-linger 0: the open page must not keep the graph up after the run (timed to its end).
    child = subprocess.Popen(
        [str(RUN), SGIM_D, "--seed", str(seed), "--movements", str(movements), "--teacher",
         "web", "--web-port", "0", "--web-linger", "0", "--runs-dir", str(out), "--name",
         name, "--quiet"],
        stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    stats: dict = {}
    started = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load = os.getloadavg()[0]
    if page:
        viewer = threading.Thread(target=watch, args=(out / name, child, stats))
        viewer.start()
    _, status, usage = os.wait4(child.pid, 0)  # the launcher and every node it waited for
    child.returncode = code = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - started
    if page:
        viewer.join()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    run_cpu = usage.ru_utime + usage.ru_stime
    # What else our children used meanwhile: the browser and Playwright's driver.
    page_cpu = (after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime) - run_cpu
    if code != 0:
        raise SystemExit(f"run {name} failed (exit {code}); see {out / name}")
    log = node_log(out / name / "logs", "social_interaction").read_text()
    count, seconds = FINISHED.search(log).groups()
    return {"name": name, "run_s": float(seconds), "wall_s": wall, "movements": int(count),
            "run_cpu": run_cpu, "page_cpu": max(0.0, page_cpu), "load": load, **stats}


def watch(run_dir: Path, child: subprocess.Popen, stats: dict) -> None:
    """Open the page as soon as the node serves it; read its numbers until the run ends."""
    from teacher.web.headless import browser_page

    address = run_dir / "web_teacher.url"
    while not address.exists() and child.poll() is None:
        time.sleep(0.1)
    if child.poll() is not None:
        return
    with browser_page() as page:
        page.goto(address.read_text().strip())
        while child.poll() is None:
            try:
                latest = page.evaluate("({...window.teacherStats, now: performance.now()})")
            except Exception:  # the page is between two states of the DOM: try again
                latest = None
            if latest:
                stats["page"] = latest
            time.sleep(0.5)


def describe_page(stats: dict) -> str:
    p = stats.get("page")
    if not p or not p["updates"]:
        return "page: no update seen"
    seconds = (p["now"] - p["started"]) / 1000
    return (f"page: {p['updates'] / seconds:.1f} updates/s, {p['landings']} landings drawn, "
            f"update {p['totalMs'] / p['updates']:.2f} ms mean, {p['maxMs']:.1f} ms max, "
            f"{p['slow']} over 50 ms")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--movements", type=int, default=1000)
    p.add_argument("--repeats", type=int, default=3, help="pairs of runs (default 3)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--page-only", action="store_true",
                   help="only runs with the page open (to measure the page on a long run)")
    args = p.parse_args()
    out = Path(tempfile.mkdtemp(prefix="bench-web-"))
    results: dict[bool, list[dict]] = {False: [], True: []}
    for k in range(args.repeats):
        for page in ((True,) if args.page_only else (False, True)):
            r = one_run(out, f"{'page' if page else 'nopage'}{k}", args.movements, args.seed,
                        page)
            results[page].append(r)
            print(f"{r['name']:8s} run {r['run_s']:6.1f} s  wall {r['wall_s']:6.1f} s  "
                  f"CPU run {r['run_cpu']:6.1f} s  browser {r['page_cpu']:5.1f} s  "
                  f"load {r['load']:4.1f}  " + (describe_page(r) if page else ""), flush=True)
    def median(page: bool, key: str) -> float:
        return statistics.median(r[key] for r in results[page])

    with_page = median(True, "run_s")
    cpu_with = median(True, "run_cpu") + median(True, "page_cpu")
    print(f"\n{args.movements} movements, seed {args.seed}, {args.repeats} repeat(s); with the "
          f"page open: run time {with_page:.1f} s, CPU {median(True, 'run_cpu'):.1f} s (run) "
          f"+ {median(True, 'page_cpu'):.1f} s (browser)")
    if results[False]:
        without, cpu_without = median(False, "run_s"), median(False, "run_cpu")
        print(f"without a page: run time {without:.1f} s, CPU {cpu_without:.1f} s")
        nodes = median(True, "run_cpu")
        print(f"overhead of the page: run time {100 * (with_page - without) / without:+.1f} %, "
              f"CPU of the run's nodes {100 * (nodes - cpu_without) / cpu_without:+.1f} %, "
              f"CPU with the browser's {100 * (cpu_with - cpu_without) / cpu_without:+.1f} % "
              "(target < 5 %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
