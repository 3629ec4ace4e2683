"""Chaos soak: short runs through the graph under node kills, launcher kills, rogue publishers
and a disk that fills, each resumed until it finishes, then checked against an uninterrupted
run of the same seed (issue 31, item 7).

Every run is sgim-d, 300 movements, a teacher every 50, evaluations every 100. Its faults are
drawn from the run's own seed (one to three of: kill a node of the graph, kill the launcher,
publish forged records while it runs, run its first part on a disk that fills), and it is
resumed (--resume) until it finishes, at most 6 times. Then two checks that share no code with
the readers of the project:
  - a rosbags-only pass over every segment of its bag: the movements whose HMAC the run's key
    verifies (stdlib hmac) count 1..300, each once (a re-execution replacing its index);
  - the project's rebuild, compared with an uninterrupted run of the same seed made by the
    single-process runner (which the graph equals: tests/ros/test_graph_runs.py): the movements
    before the first interruption must be the reference's, bit for bit (after it, a resumed run
    restarts its random streams: the documented difference); every teacher turn has its word
    and, when something was shown, the learner took it; every evaluation point is there; the
    interest tree holds every competence recorded.
A run is *silently wrong* when its metadata says finished and a check fails. Printed: the
counts (runs, faults by kind, runs finished, resumes, failures with their message, silently
wrong) and one line per run.

    source ros_ws/env.sh && python benchmarks/chaos_soak.py --runs 20
"""

from __future__ import annotations

import argparse
import hashlib
import hmac
import json
import os
import random
import shutil
import signal
import struct
import subprocess
import tempfile
import threading
import time
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from sgim_nodes.core.learner_registry import SGIM_D

REPO = Path(__file__).resolve().parents[1]
RUN = str(REPO / "ros_ws" / "run_experiment.sh")
MOVEMENTS, PERIOD, EVAL_EVERY = 300, 50, 100
NODES = ("sim_bridge", "low_level_explorer", "evaluator", "social_interaction",
         "interest_computer", "goal_generator", "teacher", "imitation", "recorder", "markers")
FAULTS = ("node-kill", "launcher-kill", "rogue", "full-disk")
MAX_RESUMES = 6


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
    params = str(run_dir / "params")
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            text = cmdline.read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if f"/{executable} " in text and params in text:
            return int(cmdline.parent.name)
    return None


def progress(run_dir: Path) -> int:
    """The latest movement count the arbiter logged (0 when none yet)."""
    import re

    best = 0
    for log in run_dir.glob("logs/**/social_interaction.log"):
        try:
            for found in re.findall(r"(\d+)/\d+ movements", log.read_text(errors="replace")):
                best = max(best, int(found))
        except OSError:
            pass
    return best


def run_argv(seed: int, runs: Path, domain: int) -> list[str]:
    return [RUN, SGIM_D, "--seed", str(seed), "--movements", str(MOVEMENTS),
            "--demonstration-period", str(PERIOD), "--eval-every", str(EVAL_EVERY), "--runs-dir",
            str(runs), "--name", f"soak{seed}", "--domain", str(domain), "--quiet", "--timeout",
            "600"]


class Rogue(threading.Thread):
    """Publishes forged records into the run's domain while it runs: re-executions of real
    movements with another outcome, duplicates, far indices, bad demonstrations, bad
    competences."""

    def __init__(self, domain: int, seed: int) -> None:
        super().__init__(daemon=True)
        self.domain, self.seed, self.stop = domain, seed, threading.Event()
        self.sent = 0

    def run(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        from sgim_msgs.msg import Competence, Demonstration, Movement
        from sgim_ros import qos

        os.environ["ROS_DOMAIN_ID"] = str(self.domain)
        context = rclpy.Context()
        rclpy.init(context=context)
        node = rclpy.create_node(f"rogue{self.seed}", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        seen: list = []
        node.create_subscription(Movement, "/movements", seen.append, qos.RECORDS)
        moves = node.create_publisher(Movement, "/movements", qos.RECORDS)
        demos = node.create_publisher(Demonstration, "/demonstrations", qos.RECORDS)
        comps = node.create_publisher(Competence, "/competences", qos.RECORDS)
        rng = np.random.default_rng(self.seed)
        try:
            while not self.stop.is_set():
                executor.spin_once(timeout_sec=0.2)
                if not seen or rng.random() > 0.3:
                    continue
                last = seen[-1]
                kind = int(rng.integers(4))
                if kind == 0:  # a forged re-execution right after the real record
                    moves.publish(Movement(index=last.index, process=last.process, status=0,
                                           action=list(last.action), outcome=[0.99, 0.99],
                                           goal=list(last.goal), goal_index=last.goal_index,
                                           attempt=1, signature=list(last.signature)))
                elif kind == 1:  # a duplicate of an earlier index, and one far ahead
                    moves.publish(Movement(index=max(1, last.index - 3), process=0, status=0,
                                           action=list(rng.uniform(-1, 1, 24)),
                                           outcome=[0.5, 0.5]))
                    moves.publish(Movement(index=last.index + 50, process=0, status=0,
                                           action=[0.0] * 24, outcome=[0.1, 0.1]))
                elif kind == 2:  # demonstrations with NaN and an unknown teaching entry
                    demos.publish(Demonstration(index=900 + self.sent, movement_index=last.index,
                                                action=[float("nan")] * 24, outcome=[0.1, 0.1],
                                                teaching_set_index=1, source="human"))
                    demos.publish(Demonstration(index=901 + self.sent, movement_index=last.index,
                                                action=[0.1] * 24, outcome=[0.1, 0.1],
                                                teaching_set_index=2**31 - 1, source="human"))
                else:  # a competence of NaN
                    comps.publish(Competence(goal=[0.1, 0.1], competence=float("nan"),
                                             movements_used=2, movement_index=last.index))
                self.sent += 1
        finally:
            node.destroy_node()
            executor.shutdown()
            rclpy.shutdown(context=context)


def segment(soak: Soak, argv: list[str], run_dir: Path, domain: int, kills: bool,
            rogue: bool) -> str:
    """One launch (a first part or a resume) with its faults; its launcher's last line."""
    rng = random.Random(soak.seed * 7 + soak.resumes)
    forger = Rogue(domain, soak.seed) if rogue else None
    child = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if forger:
        forger.start()
    if kills:
        at = progress(run_dir) + rng.randint(20, 120)
        deadline = time.monotonic() + 600
        while progress(run_dir) < at and child.poll() is None and time.monotonic() < deadline:
            time.sleep(0.2)
        if child.poll() is None:
            if "node-kill" in soak.faults:
                soak.killed = rng.choice(NODES)
                pid = node_pid(run_dir, soak.killed)
                if pid:
                    os.kill(pid, signal.SIGKILL)
            if "launcher-kill" in soak.faults:
                time.sleep(rng.random() * 2)
                child.kill()
    output, _ = child.communicate(timeout=900)
    if forger:
        forger.stop.set()
        forger.join(30)
    return (output.strip().splitlines() or [""])[-1]


def first_segment(soak: Soak, runs: Path, domain: int, workdir: Path) -> None:
    """The run's first part with its faults. On a disk that fills, the first part runs on a
    200 kB tmpfs of its own (a mount namespace), and its folder is then moved to this disk;
    the kills, if any, strike the first resume instead."""
    argv = run_argv(soak.seed, runs, domain)
    run_dir = runs / f"soak{soak.seed}"
    kills = "node-kill" in soak.faults or "launcher-kill" in soak.faults
    if "full-disk" not in soak.faults:
        soak.outcome = segment(soak, argv, run_dir, domain, kills, "rogue" in soak.faults)
        return
    mount = workdir / f"disk{soak.seed}"
    mount.mkdir()
    script = (f"mount -t tmpfs -o size=200k tmpfs {mount} && "
              + " ".join(argv).replace(str(runs), str(mount))
              + f"; cp -a {mount}/soak{soak.seed} {runs}/")
    soak.outcome = segment(soak, ["unshare", "--user", "--map-root-user", "--mount", "sh",
                                  "-c", script], run_dir, domain, False, "rogue" in soak.faults)
    if kills:
        soak.resumes += 1
        soak.outcome = segment(soak, [RUN, "--resume", str(run_dir), "--quiet", "--domain",
                                      str(domain)], run_dir, domain, True, False)


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


def signed_indices(run_dir: Path) -> list[int]:
    """No project code: the mcap library reads every segment's MCAP file as far as it is
    whole (a recorder that met a full disk leaves it truncated), rosbags decodes the
    movements with the definitions the file embeds, and the stdlib's hmac keeps those the
    run's key verifies; their indices in order, a re-execution replacing its index."""
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader
    from rosbags.typesys import Stores, get_typestore

    key = bytes.fromhex((run_dir / "record.key").read_text().strip())
    seen: set[int] = set()
    order: list[int] = []
    files = sorted(run_dir.glob("bag*/*.mcap"),
                   key=lambda f: (len(f.parent.name), f.parent.name))
    for file in files:
        store = get_typestore(Stores.ROS2_JAZZY)
        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        try:
            with file.open("rb") as stream:
                for record in StreamReader(stream, emit_chunks=False).records:
                    if isinstance(record, Schema):
                        schemas[record.id] = record
                    elif isinstance(record, Channel):
                        channels[record.id] = record
                    elif isinstance(record, Message):
                        channel = channels[record.channel_id]
                        if channel.topic.rsplit("/", 1)[-1] != "movements":
                            continue
                        schema = schemas[channel.schema_id]
                        if schema.name not in store.types:
                            store.register(_definitions(schema.name, schema.data.decode()))
                        m = store.deserialize_cdr(record.data, schema.name)
                        if _signed(key, m) and int(m.index) not in seen:
                            seen.add(int(m.index))
                            order.append(int(m.index))
        except Exception:  # the file ends where its recorder stopped: what came before counts
            pass
    return order


def _definitions(name: str, text: str) -> dict:
    """The types of a ros2msg schema as an MCAP file embeds them (the type, then its
    dependencies after '=' lines)."""
    from rosbags.typesys import get_types_from_msg

    parts = text.split("=" * 80 + "\n")
    types = dict(get_types_from_msg(parts[0], name))
    for part in parts[1:]:
        header, _, body = part.partition("\n")
        types.update(get_types_from_msg(body, header.removeprefix("MSG: ").strip()))
    return types


def _signed(key: bytes, m) -> bool:
    body = struct.pack("<QBBBQ", int(m.index), int(m.attempt), int(m.process), int(m.status),
                       int(m.goal_index))
    for values in (m.action, m.outcome, m.goal):
        data = np.asarray(values, dtype="<f8").ravel()
        body += struct.pack("<I", data.size) + data.tobytes()
    mac = hmac.new(key, body, hashlib.sha256).digest()[:16]
    return hmac.compare_digest(mac, bytes(bytearray(m.signature)))


def reference_movements(seed: int) -> list[dict]:
    """The movements of an uninterrupted run of the same seed and settings, made by the
    single-process runner (the graph makes its very movements)."""
    from sgim_nodes.core.learner_registry import make_learner
    from sgim_nodes.core.runner import build_world, run
    from sgim_nodes.core.social_config import SocialConfig

    world = build_world("fishing", seed)
    learner = make_learner(SGIM_D, world.env.action_dim, world.env.outcome_dim, seed,
                           scale=world.scale)
    records: list[dict] = []
    run(learner, world, MOVEMENTS, EVAL_EVERY, seed, records.append,
        SocialConfig(demonstration_period=PERIOD))
    return [r for r in records if r["type"] == "movement"]


def check(soak: Soak, run_dir: Path) -> None:
    """The checks of the module's doc; problems appended to soak.problems."""
    from sgim_nodes.bag.rebuild import rebuild_from_records
    from sgim_nodes.bag.resume import load_run_folder

    order = signed_indices(run_dir)
    if order != list(range(1, MOVEMENTS + 1)):
        soak.problems.append(f"signed movements are not 1..{MOVEMENTS} once each "
                             f"({len(order)} found)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        records = load_run_folder(run_dir)
    state = rebuild_from_records(records)
    if state.n_movements != MOVEMENTS:
        soak.problems.append(f"rebuild holds {state.n_movements} movements")
    meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())
    resumed = meta.get("resumed") or []
    cut = resumed[0]["from_movement"] if resumed else MOVEMENTS
    reference = reference_movements(soak.seed)
    for m, r in zip(records.movements[:cut], reference[:cut], strict=False):
        if not np.array_equal(m.action, np.asarray(r["action"])):
            soak.problems.append(f"movement {m.index} (before the first interruption at "
                                 f"{cut}) differs from the uninterrupted run")
            break
    turns = range(0, MOVEMENTS, PERIOD)
    words = {d.movement_index for d in records.demonstrations if not d.help_request}
    shown = {d.movement_index for d in records.demonstrations if d.shown}
    taken = {d.movement_index for d in records.demonstrations_taken}
    for k in turns:
        if k not in words:
            soak.problems.append(f"no teacher's word at turn {k}")
        elif k in shown and k not in taken:
            soak.problems.append(f"turn {k}: a demonstration shown, none taken")
    points = {e.movement_index for e in records.evaluations}
    missing = [p for p in range(0, MOVEMENTS + 1, EVAL_EVERY) if p not in points]
    if missing:
        soak.problems.append(f"no evaluation at {missing}")
    if state.n_competences != len(records.competences):
        soak.problems.append(f"the tree holds {state.n_competences} competences, the bag "
                             f"{len(records.competences)}")
    if state.region_map_matches() is False:
        soak.problems.append("the rebuilt tree's leaves are not the last recorded map's")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", type=int, default=20)
    p.add_argument("--first-seed", type=int, default=0)
    p.add_argument("--keep", type=Path, help="keep the runs in this folder")
    args = p.parse_args(argv)
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
                    check(soak, run_dir)
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
