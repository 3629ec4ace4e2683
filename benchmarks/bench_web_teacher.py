"""The web teacher's cost to a run, and the page's responsiveness, in a real headless browser.

Runs the same SGIM-D run (same seed, no demonstration: the same movements) with the web
teacher, alternately without a page and with the page open in headless Chromium, and prints
the arbiter's run time of each (from its start to its last movement and final evaluation, as
its log says; the nodes' start-up is not the page's cost), their medians and the overhead
(target: under 5 %). For the runs with a page it prints how the page kept up: updates per
second (target >= 2), the mean and longest time to apply one update, and updates over 50 ms.

    source ros_ws/env.sh
    python benchmarks/bench_web_teacher.py --movements 1000 --repeats 3
    python benchmarks/bench_web_teacher.py --movements 5000 --repeats 1 --page-only
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
RUN = REPO / "ros_ws" / "run_experiment.sh"
FINISHED = re.compile(r"run finished: (\d+) movements in ([0-9.]+) s")


def one_run(out: Path, name: str, movements: int, seed: int, page: bool) -> dict:
    child = subprocess.Popen(
        [str(RUN), "sgim-d", "--seed", str(seed), "--movements", str(movements), "--teacher",
         "web", "--web-port", "0", "--runs-dir", str(out), "--name", name, "--quiet"],
        stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    stats: dict = {}
    started = time.perf_counter()
    if page:
        viewer = threading.Thread(target=watch, args=(out / name, child, stats))
        viewer.start()
    code = child.wait()
    wall = time.perf_counter() - started
    if page:
        viewer.join()
    if code != 0:
        raise SystemExit(f"run {name} failed (exit {code}); see {out / name}")
    log = (out / name / "logs" / "social_interaction.log").read_text()
    count, seconds = FINISHED.search(log).groups()
    return {"name": name, "run_s": float(seconds), "wall_s": wall, "movements": int(count),
            **stats}


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
                  + (describe_page(r) if page else ""), flush=True)
    with_page = statistics.median(r["run_s"] for r in results[True])
    print(f"\n{args.movements} movements, seed {args.seed}, {args.repeats} repeat(s); "
          f"median run time with the page open: {with_page:.1f} s")
    if results[False]:
        without = statistics.median(r["run_s"] for r in results[False])
        print(f"median run time without a page: {without:.1f} s; overhead of the page: "
              f"{100 * (with_page - without) / without:+.1f} % (target < 5 %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
