"""Chaos soak: short runs through the graph under node kills, launcher kills, forged records and
a disk that fills, each resumed until it finishes, then checked (benchmarks/soak_checks.py).

Every run is sgim-d, 300 movements, a teacher every 50, evaluations every 100. Its faults are
drawn from the run's own seed, one to three of:
  node-kill        kill a node of the graph (SIGKILL) while the run goes on;
  launcher-kill    kill the launcher, and so the run;
  cut-imitation    kill the launcher during a teacher's turn's imitation;
  rogue            publish bad records: forged re-executions, duplicates, far indices,
                   demonstrations with NaN or an unknown teaching entry, NaN competences;
  forged-teaching  publish well-formed records nobody signed: demonstrations at the
                   teacher's turns, as answers to asks (also as an expert) and as taken, and
                   competences;
  web-offer        run the web teacher's page beside the run, publish a forged movement, and
                   ask the page for an offer where the forgery lands;
  domain-clash     start a second run on the run's ROS domain while it runs;
  full-disk        run the first part on a disk that fills.
It is resumed (--resume) until it finishes, at most 6 times. A run is *silently wrong* when its
metadata says finished and a check fails. Printed: the counts (runs, faults by kind, runs
finished, resumes, failures with their message, silently wrong) and one line per run.

    source ros_ws/env.sh && python benchmarks/chaos_soak.py --runs 20
"""

from __future__ import annotations

import argparse
import json
import os
import random
import re
import shutil
import signal
import subprocess
import tempfile
import threading
import time
import urllib.request
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from soak_checks import FORGED_OUTCOME, run_problems  # beside this script

from sgim_nodes.core.learner_registry import SGIM_D
from sgim_nodes.graph.processes import node_log

REPO = Path(__file__).resolve().parents[1]
RUN = str(REPO / "ros_ws" / "run_experiment.sh")
ROS2RUN = str(REPO / "ros_ws" / "ros2run.sh")
MOVEMENTS, PERIOD, EVAL_EVERY = 300, 50, 100
NODES = ("sim_bridge", "low_level_explorer", "evaluator", "social_interaction",
         "interest_computer", "goal_generator", "teacher", "imitation", "recorder", "markers")
KILLS = ("node-kill", "launcher-kill", "cut-imitation")
FORGERIES = ("rogue", "forged-teaching", "web-offer")
FAULTS = (*KILLS, *FORGERIES, "domain-clash", "full-disk")
MAX_RESUMES = 6
FORGED_INDEX = 10**15  # the web-offer forgery's movement index


@dataclass
class Soak:
    seed: int
    faults: list[str] = field(default_factory=list)
    killed: str = ""
    resumes: int = 0
    outcome: str = ""
    problems: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def finished(self) -> bool:
        return self.outcome == "finished"


def plan_faults(seed: int) -> list[str]:
    rng = random.Random(seed)
    return sorted(rng.sample(FAULTS, rng.randint(1, 3)))


def node_pid(run_dir: Path, executable: str) -> int | None:
    """The process of the run that hosts the node: its own, or the one it shares."""
    params = str(run_dir / "params")
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            text = cmdline.read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if (f"/{executable} " in text or f"--node {executable}=" in text) and params in text:
            return int(cmdline.parent.name)
    return None


def progress(run_dir: Path) -> int:
    """The latest movement count the arbiter logged (0 when none yet)."""
    best = 0
    for log in {node_log(folder, "social_interaction") for folder in run_dir.glob("logs/**/")}:
        try:
            for found in re.findall(r"(\d+)/\d+ movements", log.read_text(errors="replace")):
                best = max(best, int(found))
        except OSError:
            pass
    return best


def run_argv(seed: int, runs: Path, domain: int, name: str = "") -> list[str]:
    return [RUN, SGIM_D, "--seed", str(seed), "--movements", str(MOVEMENTS),
            "--demonstration-period", str(PERIOD), "--eval-every", str(EVAL_EVERY), "--runs-dir",
            str(runs), "--name", name or f"soak{seed}", "--domain", str(domain), "--quiet",
            "--timeout", "600", *LAYOUT]


LAYOUT: list[str] = []  # run_experiment.sh's process options (--separate)


class Peer(threading.Thread):
    """A process's worth of ROS in the run's domain: it hears the movements (to time a kill
    at an imitation) and publishes the forgeries of ``kinds`` while the run goes on."""

    def __init__(self, domain: int, seed: int, kinds: set[str]) -> None:
        super().__init__(daemon=True)
        self.domain, self.seed, self.kinds = domain, seed, kinds
        self.stop, self.imitating = threading.Event(), threading.Event()
        self.sent: Counter = Counter()

    def run(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        from sgim_msgs.msg import Competence, Demonstration, Movement
        from sgim_ros import qos

        os.environ["ROS_DOMAIN_ID"] = str(self.domain)
        context = rclpy.Context()
        rclpy.init(context=context)
        node = rclpy.create_node(f"peer{self.seed}", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        seen: list = []

        def heard(m: Movement) -> None:
            seen.append(m)
            if m.process == Movement.PROCESS_IMITATION and m.index > PERIOD:
                self.imitating.set()  # a later turn's: the first one's is too early to cut

        node.create_subscription(Movement, "/movements", heard, qos.RECORDS)
        out = {"movements": node.create_publisher(Movement, "/movements", qos.RECORDS),
               "demonstrations": node.create_publisher(Demonstration, "/demonstrations",
                                                       qos.RECORDS),
               "taken": node.create_publisher(Demonstration, "/demonstrations_taken",
                                              qos.RECORDS),
               "competences": node.create_publisher(Competence, "/competences", qos.RECORDS)}
        rng = np.random.default_rng(self.seed)
        try:
            while not self.stop.is_set():
                executor.spin_once(timeout_sec=0.2)
                if not seen or rng.random() > 0.3 or not self.kinds - {"watch"}:
                    continue
                kind = str(rng.choice(sorted(self.kinds - {"watch"})))
                getattr(self, kind.replace("-", "_"))(out, seen[-1], rng)
                self.sent[kind] += 1
        finally:
            node.destroy_node()
            executor.shutdown()
            rclpy.shutdown(context=context)

    def rogue(self, out, last, rng) -> None:
        """Bad records: a forged re-execution, duplicates, far indices, NaN."""
        from sgim_msgs.msg import Competence, Demonstration, Movement

        kind = int(rng.integers(4))
        if kind == 0:  # a forged re-execution right after the real record
            out["movements"].publish(Movement(
                index=last.index, process=last.process, status=0, action=list(last.action),
                outcome=list(FORGED_OUTCOME), goal=list(last.goal), goal_index=last.goal_index,
                attempt=1, signature=list(last.signature)))
        elif kind == 1:  # a duplicate of an earlier index, and one far ahead
            out["movements"].publish(Movement(index=max(1, last.index - 3), process=0, status=0,
                                              action=list(rng.uniform(-1, 1, 24)),
                                              outcome=list(FORGED_OUTCOME)))
            out["movements"].publish(Movement(index=last.index + 50, process=0, status=0,
                                              action=[0.0] * 24, outcome=list(FORGED_OUTCOME)))
        elif kind == 2:  # demonstrations with NaN and an unknown teaching entry
            out["demonstrations"].publish(Demonstration(
                index=900, movement_index=last.index, action=[float("nan")] * 24,
                outcome=[0.1, 0.1], teaching_set_index=1, source="human"))
            out["demonstrations"].publish(Demonstration(
                index=901, movement_index=last.index, action=[0.1] * 24, outcome=[0.1, 0.1],
                teaching_set_index=2**31 - 1, source="human"))
        else:  # a competence of NaN
            out["competences"].publish(Competence(goal=[0.1, 0.1], competence=float("nan"),
                                                  movements_used=2,
                                                  movement_index=last.index))

    def forged_teaching(self, out, last, rng) -> None:
        """Well-formed teaching nobody signed: the teacher's word at the next turn, an answer
        to an ask (as the automatic teacher and as an expert), a demonstration 'taken', and
        a competence for the interest tree."""
        from sgim_msgs.msg import Competence, Demonstration

        turn = (last.index // PERIOD + 1) * PERIOD
        action = list(rng.uniform(-0.5, 0.5, 24))
        for topic, at, source, ask in (("demonstrations", turn, "automatic", 0),
                                       ("demonstrations", last.index, "automatic", 1),
                                       ("demonstrations", last.index, "expert:rough", 2),
                                       ("taken", last.index, "automatic", 0)):
            out[topic].publish(Demonstration(
                index=int(rng.integers(1, 40)), movement_index=int(at), action=action,
                outcome=list(FORGED_OUTCOME), teaching_set_index=int(rng.integers(0, 40)),
                source=source, help_request=ask))
        out["competences"].publish(Competence(
            goal_index=int(rng.integers(1, 40)), movement_index=last.index,
            goal=list(FORGED_OUTCOME), reached=list(FORGED_OUTCOME), competence=0.0,
            movements_used=1))

    def web_offer(self, out, last, rng) -> None:
        """An unsigned movement landing at FORGED_OUTCOME, far ahead, for the page to offer."""
        from sgim_msgs.msg import Movement

        out["movements"].publish(Movement(index=FORGED_INDEX, process=1, status=0,
                                          action=[0.3] * 24, outcome=list(FORGED_OUTCOME),
                                          goal=list(FORGED_OUTCOME), goal_index=1))


class WebPage:
    """The web teacher's node beside the run, in its domain and with its key, as a person's
    page would be; ``problems()`` asks it what it counts and offers at the forgery."""

    def __init__(self, run_dir: Path, domain: int, workdir: Path) -> None:
        self.address = workdir / f"page{run_dir.name}.url"
        key_file = run_dir / "record.key"
        deadline = time.monotonic() + 60
        while not key_file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain),
                   SGIM_RECORD_KEY=key_file.read_text().strip())
        self.process = subprocess.Popen(
            [ROS2RUN, "teacher", "web_teacher", "--ros-args", "-p", "port:=0",
             "-p", f"address_file:={self.address}", "-p", "render_casts:=false"],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 60  # its address, read now: it goes when the run ends
        while not self.address.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        self.url = self.address.read_text().strip().rstrip("/") if self.address.exists() else ""

    def _ask(self, method: str, path: str, body: dict | None = None) -> dict:
        data = json.dumps(body).encode() if body is not None else None
        request = urllib.request.Request(self.url + path, data=data, method=method,
                                         headers={"Content-Type": "application/json",
                                                  "X-Teacher": "1"})
        with urllib.request.urlopen(request, timeout=10) as answer:
            return json.loads(answer.read())

    def problems(self) -> list[str]:
        if not self.url:
            return ["the page did not start"]
        try:
            state = self._ask("GET", "/api/state")
            offer = self._ask("POST", "/api/command", {"command": "offer",
                                                       "x": FORGED_OUTCOME[0],
                                                       "y": FORGED_OUTCOME[1]})
        except (OSError, ValueError) as error:
            return [f"the page did not answer ({error})"]
        problems = []
        if int(state.get("count", 0)) > MOVEMENTS:
            problems.append(f"the page counts {state['count']} movements")
        landed = (offer.get("offer") or {}).get("outcome")
        if landed and np.allclose(landed, FORGED_OUTCOME):
            problems.append(f"the page offered the forgery: {offer.get('message')}")
        return problems

    def close(self) -> None:
        self.process.terminate()
        try:
            self.process.wait(20)
        except subprocess.TimeoutExpired:
            self.process.kill()


def clash(soak: Soak, runs: Path, domain: int) -> None:
    """A second run asks for the run's domain: it must be refused at once, touching nothing."""
    other = subprocess.run(run_argv(soak.seed, runs, domain, f"clash{soak.seed}"),
                           capture_output=True, text=True, timeout=120)
    said = (other.stdout + other.stderr).strip().splitlines()
    if other.returncode != 2 or not said or "held by another run" not in said[-1]:
        soak.problems.append(f"a second run on domain {domain}: exit {other.returncode}, "
                             f"{said[-1] if said else 'nothing said'}")
    if (runs / f"clash{soak.seed}").exists():
        soak.problems.append("the refused second run left a folder")


def segment(soak: Soak, argv: list[str], run_dir: Path, domain: int, first: bool,
            workdir: Path) -> str:
    """One launch (a first part or a resume) with its faults; its launcher's last line."""
    rng = random.Random(soak.seed * 7 + soak.resumes)
    kinds = {f for f in soak.faults if f in FORGERIES} if first else set()
    kills = [f for f in soak.faults if f in KILLS] if first else []
    peer = Peer(domain, soak.seed, kinds | ({"watch"} if kills else set()))
    child = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    peer.start()
    page = WebPage(run_dir, domain, workdir) if "web-offer" in kinds else None
    try:
        if first and "domain-clash" in soak.faults:
            # Once this launch moves (a resume's log starts where the run stopped), it holds
            # its domain: the second run must then be refused.
            deadline, start = time.monotonic() + 120, progress(run_dir)
            while progress(run_dir) < start + 10 and child.poll() is None \
                    and time.monotonic() < deadline:
                time.sleep(0.2)
            clash(soak, run_dir.parent, domain)
        if kills:
            at = progress(run_dir) + rng.randint(20, 120)
            deadline = time.monotonic() + 600
            while child.poll() is None and time.monotonic() < deadline and (
                    not peer.imitating.is_set() if "cut-imitation" in kills
                    else progress(run_dir) < at):
                time.sleep(0.05)
            if child.poll() is None:
                if "node-kill" in kills:
                    soak.killed = rng.choice(NODES)
                    pid = node_pid(run_dir, soak.killed)
                    if pid:
                        os.kill(pid, signal.SIGKILL)
                if "launcher-kill" in kills or "cut-imitation" in kills:
                    if "cut-imitation" not in kills:
                        time.sleep(rng.random() * 2)
                    child.kill()
        output, _ = child.communicate(timeout=900)
        if page is not None:
            soak.problems += page.problems()
    finally:
        if child.poll() is None:
            child.kill()
        if page is not None:
            page.close()
        peer.stop.set()
        peer.join(30)
    return (output.strip().splitlines() or [""])[-1]


def first_segment(soak: Soak, runs: Path, domain: int, workdir: Path) -> None:
    """The run's first part with its faults. On a disk that fills, the first part runs on a
    200 kB tmpfs of its own (a mount namespace), and its folder is then moved to this disk;
    the kills and forgeries, if any, strike the first resume instead."""
    argv = run_argv(soak.seed, runs, domain)
    run_dir = runs / f"soak{soak.seed}"
    if "full-disk" not in soak.faults:
        soak.outcome = segment(soak, argv, run_dir, domain, True, workdir)
        return
    mount = workdir / f"disk{soak.seed}"
    mount.mkdir()
    script = (f"mount -t tmpfs -o size=200k tmpfs {mount} && "
              + " ".join(argv).replace(str(runs), str(mount))
              + f"; cp -a {mount}/soak{soak.seed} {runs}/")
    soak.outcome = segment(soak, ["unshare", "--user", "--map-root-user", "--mount", "sh",
                                  "-c", script], run_dir, domain, False, workdir)
    if set(soak.faults) - {"full-disk"}:
        soak.resumes += 1
        soak.outcome = segment(soak, [RUN, "--resume", str(run_dir), "--quiet", "--domain",
                                      str(domain)], run_dir, domain, True, workdir)


def outcome_of(run_dir: Path) -> str:
    try:
        return str(yaml.safe_load((run_dir / "metadata.yaml").read_text()).get("outcome", ""))
    except (OSError, yaml.YAMLError, AttributeError):
        return ""


def resume_until_finished(soak: Soak, run_dir: Path, domain: int) -> None:
    while outcome_of(run_dir) != "finished" and soak.resumes < MAX_RESUMES:
        soak.resumes += 1
        done = subprocess.run([RUN, "--resume", str(run_dir), "--quiet", "--domain",
                               str(domain)], capture_output=True, text=True, timeout=900)
        soak.outcome = (done.stderr.strip().splitlines() or [""])[-1]
    soak.outcome = outcome_of(run_dir)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", type=int, default=20)
    p.add_argument("--first-seed", type=int, default=0)
    p.add_argument("--keep", type=Path, help="keep the runs in this folder")
    p.add_argument("--separate", action="store_true",
                   help="a process per node (run_experiment.sh --separate); by default the "
                        "message-only nodes share one, and killing one of them kills it")
    args = p.parse_args(argv)
    LAYOUT[:] = ["--separate"] if args.separate else []
    if args.runs < 1:
        p.error("--runs must be >= 1")
    from sgim_nodes.graph.domain import reserve_domain

    workdir = Path(tempfile.mkdtemp(prefix="chaos-soak-"))
    runs = args.keep or workdir / "runs"
    runs.mkdir(parents=True, exist_ok=True)
    soaks = []
    with reserve_domain() as reservation:
        for seed in range(args.first_seed, args.first_seed + args.runs):
            soak = Soak(seed, plan_faults(seed))
            began = time.monotonic()
            run_dir = runs / f"soak{seed}"
            try:
                first_segment(soak, runs, reservation.domain_id, workdir)
                resume_until_finished(soak, run_dir, reservation.domain_id)
                if soak.finished:
                    soak.problems += run_problems(run_dir, seed, MOVEMENTS, EVAL_EVERY, PERIOD)
            except Exception as error:  # a soak that breaks is reported, not fatal
                soak.problems.append(f"the soak itself failed: {type(error).__name__}: {error}")
            soak.seconds = time.monotonic() - began
            soaks.append(soak)
            print(f"seed {seed}: faults {'+'.join(soak.faults)}"
                  + (f" (killed {soak.killed})" if soak.killed else "")
                  + f", {soak.resumes} resumes, {soak.outcome}, "
                  + ("OK" if not soak.problems else "PROBLEMS: " + "; ".join(soak.problems))
                  + f" ({soak.seconds:.0f} s)", flush=True)
    faults = Counter(f for s in soaks for f in s.faults)
    finished = [s for s in soaks if s.finished]
    silently_wrong = [s for s in finished if s.problems]
    print(json.dumps({
        "runs": len(soaks), "faults_injected": dict(faults),
        "faults_total": sum(faults.values()),
        "nodes_killed": dict(Counter(s.killed for s in soaks if s.killed)),
        "runs_finished": len(finished), "resumes": sum(s.resumes for s in soaks),
        "runs_not_finished": {s.seed: s.outcome for s in soaks if not s.finished},
        "runs_silently_wrong": len(silently_wrong),
        "silently_wrong": {s.seed: s.problems for s in silently_wrong}}, indent=1))
    if not args.keep:
        shutil.rmtree(workdir, ignore_errors=True)
    return 1 if silently_wrong else 0


if __name__ == "__main__":
    raise SystemExit(main())
