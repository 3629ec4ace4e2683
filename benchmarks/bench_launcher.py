"""How fast a run's processes go when its launcher goes, and whether its domain stays held.

Why: issue 12 found 7 nodes running forever after a SIGKILL of run_experiment.sh, and a new
run taking their domain. Each trial starts a random-learner run, lets it make movements,
then, at a random moment, stops the launcher with --signal (SIGKILL by default: it cannot
clean up) and measures:
  - the time until no process of the run is left (nodes end on their own: parent-death
    signal, then the watchdog on the launcher's pipe);
  - whether the run's ROS domain could be taken by another run while one of them lived;
  - what metadata.yaml says afterwards.

    source ros_ws/env.sh && python benchmarks/bench_launcher.py [--trials 5] [--signal INT]
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "sgim_nodes")]

from sgim_nodes.core.learner_registry import RANDOM  # noqa: E402
from sgim_nodes.graph.domain import reserve_domain  # noqa: E402
from sgim_nodes.graph.processes import node_log, run_node_pids  # noqa: E402

RUN = str(REPO / "ros_ws" / "run_experiment.sh")


def movements_logged(run_dir: Path) -> bool:
    log = node_log(run_dir / "logs", "social_interaction")
    return log.exists() and " movements (" in log.read_text(errors="replace")


def trial(tmp: Path, k: int, sig: signal.Signals, rng: random.Random) -> dict:
    run_dir = tmp / f"trial{k}"
    launcher = subprocess.Popen(
        [RUN, RANDOM, "--movements", "2000", "--eval-every", "0", "--runs-dir", str(tmp),
         "--name", run_dir.name, "--quiet"], stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 180
    while not movements_logged(run_dir):
        if time.monotonic() > deadline or launcher.poll() is not None:
            launcher.kill()
            raise RuntimeError(f"trial {k}: the run did not start")
        time.sleep(0.1)
    time.sleep(rng.uniform(0.0, 3.0))
    domain = yaml.safe_load((run_dir / "metadata.yaml").read_text())["ros_domain_id"]
    processes = len(run_node_pids(run_dir))
    stopped = time.monotonic()
    os.kill(launcher.pid, sig)
    launcher.wait(timeout=120)
    taken_while_alive = False
    while run_node_pids(run_dir):
        with reserve_domain(preferred=domain) as other:
            if other.domain_id == domain and run_node_pids(run_dir):
                taken_while_alive = True
        if time.monotonic() - stopped > 120:
            break
        time.sleep(0.02)
    gone = time.monotonic() - stopped
    left = run_node_pids(run_dir)
    for pid in left:  # a failed trial must not leave them behind either
        os.kill(pid, signal.SIGKILL)
    meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())
    return {"processes": processes, "gone_s": gone, "left": len(left),
            "domain_taken_while_alive": taken_while_alive, "outcome": meta.get("outcome")}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--trials", type=int, default=5)
    p.add_argument("--signal", default="KILL", help="KILL, INT, TERM or HUP (default KILL)")
    p.add_argument("--seed", type=int, default=None)
    args = p.parse_args()
    sig = signal.Signals[f"SIG{args.signal.upper().removeprefix('SIG')}"]
    rng = random.Random(args.seed)
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.trials):
            result = trial(Path(tmp), k, sig, rng)
            results.append(result)
            print(f"trial {k}: {sig.name} to the launcher of {result['processes']} processes: "
                  f"all gone after {result['gone_s']:.2f} s, left {result['left']}, domain "
                  f"taken while one lived: {result['domain_taken_while_alive']}, outcome "
                  f"{result['outcome']!r}", flush=True)
    gone = [r["gone_s"] for r in results]
    print(f"{sig.name}, {len(results)} trials: processes gone after median "
          f"{statistics.median(gone):.2f} s, max {max(gone):.2f} s; left behind: "
          f"{sum(r['left'] for r in results)}; domain taken while a process lived: "
          f"{sum(r['domain_taken_while_alive'] for r in results)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
