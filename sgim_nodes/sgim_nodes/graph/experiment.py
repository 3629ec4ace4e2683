"""Run one learning experiment through the node graph and leave one bag per run.

Starts every node of the graph as its own process (the way `ros2 run` does), in a ROS domain
of its own with discovery kept on this host, shows the run's progress, waits for its end,
stops every node cleanly and writes the run's metadata beside its bag:

    runs/<learner>-seed<N>-<time>/
        bag/            the rosbag2 recording (MCAP), every topic of the run
        params.yaml     the parameters every node was started with
        metadata.yaml   learner, seed, parameters, versions, timing, how it ended
        logs/           one log per node

Ctrl-C stops every node (the recorder closes its bag, which stays readable).
"""

from __future__ import annotations

import argparse
import contextlib
import ipaddress
import os
import platform
import secrets
import signal
import subprocess
import sys
import time
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import yaml

from sgim_nodes.bag.resume import next_segment, segments
from sgim_nodes.core.learners import GOAL_BABBLERS, LEARNER_NAMES
from sgim_nodes.graph.domain import isolated_ros_environment, reserve_domain
from sgim_nodes.graph.processes import ProcessGroup

REPO = Path(__file__).resolve().parents[3]
ROS2RUN = REPO / "ros_ws" / "ros2run.sh"
LEARNER_CONFIG = REPO / "sgim_nodes" / "config" / "learner.yaml"
SOCIAL = ("sgim-d", "demo-only")
# The simulator holds no learning state and its clients retry a call it never answered
# (sim_client.py), so it is restarted when it dies; the other nodes hold the learner's memory,
# tree or count, or serve calls that are not retried: losing one ends the run, clearly.
RESPAWNED = ("sim_bridge",)
MAX_RESPAWNS = 3
# The arbiter only knows synchronous (automatic) and asynchronous (human) demonstrations.
TEACHER_MODES = {"automatic": "automatic", "human": "human", "web": "human",
                 "external": "human"}
FOREVER = ("forever", "inf", "-1")  # --wait-for-teacher values that mean "until it acts"
WEB_TOKEN_MIN = 16  # the web teacher's own minimum (teacher.web.server.MIN_TOKEN)


def is_loopback(host: str) -> bool:
    """Whether the web teacher would serve this machine only (no token needed)."""
    try:
        return host == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def nodes_for(learner: str, teacher: str, markers: bool = True,
              web: bool = False) -> list[tuple[str, str]]:
    """(package, executable) of every node the learner needs, the arbiter last."""
    nodes = [("sgim_nodes", "recorder"), ("sim_bridge", "sim_bridge"),
             ("sgim_nodes", "evaluator")]
    if markers:
        nodes.append(("sgim_nodes", "markers"))
    if learner in GOAL_BABBLERS:
        nodes += [("sgim_nodes", "interest_computer"), ("sgim_nodes", "goal_generator"),
                  ("sgim_nodes", "low_level_explorer")]
    if learner in SOCIAL:
        nodes.append(("sgim_nodes", "imitation"))
        if teacher == "automatic":
            nodes.append(("teacher", "teacher"))
        elif web:
            nodes.append(("teacher", "web_teacher"))
    nodes.append(("sgim_nodes", "social_interaction"))
    return nodes


def parameters(args: argparse.Namespace, run_dir: Path) -> dict[str, Any]:
    """Every node reads the same file: the learner defaults, then this run's choices."""
    values = dict(yaml.safe_load(LEARNER_CONFIG.read_text())["/**"]["ros__parameters"])
    for item in args.param:
        name, _, text = item.partition("=")
        if not name or not _:
            raise SystemExit(f"--param expects NAME=VALUE, got {item!r}")
        values[name] = yaml.safe_load(text)
    values.update(learner=args.learner, seed=args.seed, movements=args.movements,
                  eval_every=args.eval_every, demonstration_period=args.period,
                  teacher=TEACHER_MODES[args.teacher] if args.learner in SOCIAL else "none",
                  output=str(run_dir / "bag"), storage=args.storage,
                  wait_for_teacher=args.wait_for_teacher,
                  wait_for_recorder=True)  # records start only once the recorder hears them
    if args.teacher == "web":
        values.update(host=args.web_host, port=args.web_port, token=args.web_token,
                      address_file=str(run_dir / "web_teacher.url"))
    return values


def wait_seconds(text: str) -> float:
    """--wait-for-teacher: seconds >= 0, or forever (the arbiter's -1)."""
    if text.strip().lower() in FOREVER:
        return -1.0
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds or 'forever', got {text!r}") from None
    if not value >= 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected seconds >= 0 or 'forever', got {text!r}")
    return value


def versions() -> dict[str, str]:
    from importlib import metadata

    found = {"python": platform.python_version(), "platform": platform.platform()}
    for dist in ("ros-jazzy-rclpy", "pybullet", "numpy", "scipy", "rosbags"):
        try:
            found[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            found[dist] = "absent"
    try:
        found["git_commit"] = subprocess.run(
            ["git", "-C", str(REPO), "describe", "--always", "--dirty"], capture_output=True,
            text=True, timeout=10).stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        found["git_commit"] = "unknown"
    return found


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="ros_ws/run_experiment.sh",
        description="Run one learner through the ROS 2 node graph and record the run to a bag "
                    "in runs/. Example: ros_ws/run_experiment.sh sgim-d --seed 3 "
                    "--movements 5000")
    p.add_argument("learner", choices=LEARNER_NAMES, nargs="?",
                   help="which learner to run (not with --resume)")
    p.add_argument("--resume", type=Path, metavar="RUN_DIR",
                   help="resume an interrupted run from its recordings, to its movement "
                        "budget; the new recording goes beside the old ones (bag.resumeN)")
    p.add_argument("--seed", type=int, default=0, help="seed of the run (default: 0)")
    p.add_argument("--movements", type=int, default=5000,
                   help="movement budget; the paper's is 5000 (default: %(default)s)")
    p.add_argument("--eval-every", type=int, default=250,
                   help="movements between evaluations; paper 250 (default: %(default)s)")
    p.add_argument("--period", type=int, default=150,
                   help="movements between demonstrations; paper 150 (default: %(default)s)")
    p.add_argument("--teacher", choices=("automatic", "human", "web", "external"),
                   default="automatic",
                   help="automatic: the teacher node, every --period movements; human: you, at "
                        "the human_input prompt in this terminal; web: you, on the web_teacher "
                        "page (its address is printed); external: no teacher node, "
                        "demonstrations come from any other publisher at any time")
    p.add_argument("--wait-for-teacher", type=wait_seconds, default=0.0, metavar="SECONDS",
                   help="human or web teacher: stop every --period movements and wait this "
                        "long for a demonstration (0: never wait; 'forever': until the "
                        "teacher demonstrates or resumes). Default: 0")
    p.add_argument("--web-port", type=int, default=8765,
                   help="web teacher: the page's port (0: any free one; default %(default)s)")
    p.add_argument("--web-host", default="127.0.0.1",
                   help="web teacher: the interface to serve on (default: this machine only; "
                        "another one needs an access token, generated unless --web-token)")
    p.add_argument("--web-token", default="",
                   help="web teacher: the access token the page's address must carry")
    p.add_argument("--no-markers", action="store_true",
                   help="do not start the markers node (MarkerArray topics for rviz2 and "
                        "Foxglove, recorded in the bag)")
    p.add_argument("--runs-dir", type=Path, default=REPO / "runs",
                   help="where the run folder is made (default: runs/)")
    p.add_argument("--name", help="run folder name (default: <learner>-seed<N>-<time>)")
    p.add_argument("--storage", choices=("mcap", "sqlite3"), default="mcap",
                   help="bag storage (default: mcap)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="override any node parameter, e.g. --param goal_budget=20")
    p.add_argument("--domain", type=int, default=None,
                   help="use this ROS_DOMAIN_ID as it is, e.g. to join a graph from a test "
                        "(default: reserve a free one)")
    p.add_argument("--timeout", type=float, default=0,
                   help="abort the run after this many seconds (default: none)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    if (args.learner is None) == (args.resume is None):
        p.error("give a learner, or --resume RUN_DIR (not both)")
    for name in ("movements", "period"):
        if getattr(args, name) < 1:
            p.error(f"--{name} must be >= 1")
    if args.seed < 0 or args.eval_every < 0:
        p.error("--seed and --eval-every must be >= 0")
    if not 0 <= args.web_port <= 65535:
        p.error("--web-port must be in 0..65535")
    if args.teacher == "web":
        if not is_loopback(args.web_host) and not args.web_token:
            args.web_token = secrets.token_urlsafe(18)
        if args.web_token and len(args.web_token) < WEB_TOKEN_MIN:
            p.error(f"--web-token must have at least {WEB_TOKEN_MIN} characters")
    if args.wait_for_teacher and args.teacher not in ("human", "web"):
        p.error("--wait-for-teacher needs a human teacher (--teacher human or web)")
    return args


class Progress:
    """Follows run_status with a small rclpy node of the launcher's own."""

    def __init__(self, total: int, quiet: bool) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from tqdm import tqdm

        from sgim_msgs.msg import RunStatus
        from sgim_ros import qos

        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = Node("experiment_launcher", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.state: int | None = None
        self.message = ""
        self.bar = tqdm(total=total, disable=quiet, unit="mv", file=sys.stderr)
        self.node.create_subscription(RunStatus, "run_status", self._on_status, qos.RECORDS)
        self.finished_state = (RunStatus.STATE_FINISHED, RunStatus.STATE_ABORTED)
        self.ok_state = RunStatus.STATE_FINISHED

    def _on_status(self, msg) -> None:
        self.bar.update(max(0, msg.movement_index - self.bar.n))
        self.state, self.message = msg.state, msg.message

    def spin(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.05)

    def say(self, text: str) -> None:
        """A line above the progress bar."""
        self.bar.write(text, file=sys.stderr)

    @property
    def over(self) -> bool:
        return self.state in self.finished_state

    def close(self) -> None:
        self.bar.close()
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)


def prepare_resume(args: argparse.Namespace) -> tuple[Path, dict[str, Any], dict[str, Any],
                                                        str] | None:
    """The run folder, its parameters and metadata, and the new segment's name."""
    run_dir = args.resume
    try:
        meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())
        params = yaml.safe_load((run_dir / "params.yaml").read_text())["/**"]["ros__parameters"]
    except (OSError, yaml.YAMLError, KeyError, TypeError) as error:
        print(f"run_experiment: {run_dir} is not a run folder ({error})", file=sys.stderr)
        return None
    segment = next_segment(run_dir)
    params.update(resume_from=str(run_dir), resume_segments=len(segments(run_dir)),
                  output=str(segment))
    args.learner, args.seed, args.movements = meta["learner"], meta["seed"], meta["movements"]
    return run_dir, params, meta, segment.name


def _interrupt(*_: object) -> None:
    raise KeyboardInterrupt


def run(args: argparse.Namespace) -> int:
    if args.resume is not None:
        prepared = prepare_resume(args)
        if prepared is None:
            return 2
        run_dir, params, meta, segment = prepared
        if meta.get("outcome") == "finished":
            print(f"run_experiment: {run_dir} already finished; nothing to resume",
                  file=sys.stderr)
            return 0
        params_file = run_dir / f"params.{segment}.yaml"
        log_dir = run_dir / "logs" / segment
        meta.setdefault("resumed", []).append(
            {"segment": segment, "at": datetime.now(UTC).isoformat()})
    else:
        stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
        run_dir = args.runs_dir / (args.name or f"{args.learner}-seed{args.seed}-{stamp}")
        if run_dir.exists():
            print(f"run_experiment: {run_dir} exists; choose another --name, or --resume it",
                  file=sys.stderr)
            return 2
        params, meta = parameters(args, run_dir), {}
        params_file, log_dir = run_dir / "params.yaml", run_dir / "logs"
    log_dir.mkdir(parents=True, exist_ok=True)
    params_file.write_text(yaml.safe_dump({"/**": {"ros__parameters": params}}))
    reservation = reserve_domain() if args.domain is None else None
    domain = args.domain if reservation is None else reservation.domain_id
    env = isolated_ros_environment(domain)
    os.environ.update(env)  # the launcher's own progress node joins the run's domain
    meta = meta or {
        "learner": args.learner, "seed": args.seed, "movements": args.movements,
        "teacher": params["teacher"], "ros_domain_id": domain,
        "started": datetime.now(UTC).isoformat(), "parameters": params, "versions": versions(),
    }
    (run_dir / "metadata.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    web = args.teacher == "web" and args.learner in SOCIAL
    nodes = nodes_for(args.learner, params["teacher"], markers=not args.no_markers, web=web)
    print(f"run_experiment: {args.learner}, seed {args.seed}, {args.movements} movements, "
          f"domain {domain}, {len(nodes)} nodes -> {run_dir}", file=sys.stderr)
    group = ProcessGroup(env=env, log_dir=log_dir)
    progress = human = None
    respawns: dict[str, int] = {}
    outcome, code = "unknown", 1
    started = time.monotonic()
    interrupted = False
    previous = signal.signal(signal.SIGTERM, _interrupt)  # SIGTERM stops a run as Ctrl-C does
    try:
        # The terminal teacher's prompt shows the count itself: no bar drawn over it.
        progress = Progress(args.movements, args.quiet or args.teacher == "human")
        packages = dict((exe, pkg) for pkg, exe in nodes)

        def launch(executable: str, log_name: str) -> subprocess.Popen:
            return group.start(log_name, [str(ROS2RUN), packages[executable], executable,
                                          "--ros-args", "--params-file", str(params_file)])

        procs = {exe: launch(exe, exe) for _, exe in nodes}
        if args.teacher == "human" and args.learner in SOCIAL:
            human = subprocess.Popen([str(ROS2RUN), "teacher", "human_input", "--ros-args",
                                      "--params-file", str(params_file)], env=env)
        arbiter, recorder = procs["social_interaction"], procs["recorder"]
        address = run_dir / "web_teacher.url" if web else None
        while True:
            progress.spin(0.2)
            if address is not None and address.exists():
                progress.say(f"run_experiment: teach at {address.read_text().strip()}")
                address = None
            if arbiter.poll() is not None or progress.over:
                break
            if recorder.poll() is not None:
                raise RuntimeError(f"the recorder stopped (exit {recorder.returncode}); see "
                                   f"{run_dir / 'logs' / 'recorder.log'}")
            for exe, child in list(procs.items()):
                if child.poll() is None or child in (arbiter, recorder):
                    continue
                if exe not in RESPAWNED or respawns.get(exe, 0) >= MAX_RESPAWNS:
                    raise RuntimeError(f"node {exe} stopped (exit {child.returncode}); see "
                                       f"{run_dir / 'logs' / exe}.log")
                respawns[exe] = respawns.get(exe, 0) + 1
                print(f"run_experiment: {exe} stopped (exit {child.returncode}); restarting "
                      f"it ({respawns[exe]}/{MAX_RESPAWNS})", file=sys.stderr)
                procs[exe] = launch(exe, f"{exe}.restart{respawns[exe]}")
            if args.timeout and time.monotonic() - started > args.timeout:
                raise RuntimeError(f"timed out after {args.timeout:g} s")
        arbiter.wait(timeout=60)
        progress.spin(0.5)  # the last status may still be on its way
        # The arbiter's exit code is the truth (0: finished); its status says why not.
        code = 0 if arbiter.returncode == 0 else 1
        outcome = "finished" if code == 0 else (
            f"aborted: {progress.message or f'arbiter exit code {arbiter.returncode}'}")
        # the recorder ends by itself once it has written the end of the run
        with contextlib.suppress(subprocess.TimeoutExpired):
            recorder.wait(timeout=30)
    except KeyboardInterrupt:
        interrupted, outcome, code = True, "interrupted by the user", 130
    except RuntimeError as error:
        outcome, code = f"failed: {error}", 1
    finally:
        signal.signal(signal.SIGTERM, previous)
        if progress is not None:
            progress.close()
        if human is not None:  # the prompt says goodbye by itself once the run is over
            with contextlib.suppress(subprocess.TimeoutExpired):
                human.wait(timeout=10 if code == 0 else 3)
        group.stop_all()
        if human is not None and human.poll() is None:
            human.terminate()
        if reservation is not None:
            reservation.release()
        meta.update(ended=datetime.now(UTC).isoformat(), outcome=outcome, restarts=respawns,
                    duration_s=round(time.monotonic() - started, 2))
        (run_dir / "metadata.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    print(f"run_experiment: {outcome}; bag and metadata in {run_dir}"
          + (" (interrupted: the bag holds what was recorded)" if interrupted else ""),
          file=sys.stderr)
    return code


def main(argv: Sequence[str] | None = None) -> int:
    return run(parse_args(argv))


if __name__ == "__main__":
    raise SystemExit(main())
