"""Run one learning experiment through the node graph and leave one bag per run.

Starts every node of the graph (graph/description.py) as its own process, the way `ros2 run`
does, in a ROS domain of its own with discovery kept on this host, shows the run's progress,
waits for its end, stops every node cleanly and writes the run's metadata beside its bag:

    runs/<learner>-seed<N>-<time>/
        bag/            the rosbag2 recording (MCAP), every topic of the run
        params.yaml     the parameters every node was started with
        metadata.yaml   learner, seed, every node's parameters, versions, timing, how it ended
        logs/           one log per node, and the launcher's own

Parameters are checked before any node starts. A run is reported finished only when the
arbiter finished it and the recorder wrote all of it; anything else is `failed` with its
reason, and a non-zero exit code. Ctrl-C (or SIGTERM, SIGHUP) stops every node, piped output
or not; nodes also stop by themselves if this launcher is killed, and the run's domain and
folder stay reserved until the last of them is gone.

Exit codes: 0 finished, 1 failed or aborted, 2 refused (bad options, parameters or run
folder), 128+N stopped by signal N (130: Ctrl-C).
"""

from __future__ import annotations

import argparse
import errno
import os
import platform
import shlex
import signal
import subprocess
import time
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import yaml

from sgim_nodes.core.config import recorded_learner
from sgim_nodes.graph import supervise
from sgim_nodes.graph.description import (
    ARBITER,
    RECORDER,
    NodeSpec,
    RunOptions,
    RunParameters,
    acts_teachers,
    check,
    fingerprint,
    graph,
    masked,
    parameters,
    unused,
)
from sgim_nodes.graph.domain import isolated_ros_environment, reserve_domain
from sgim_nodes.graph.experiment_options import REPO, default_timeout, parse_args
from sgim_nodes.graph.overrides import parse_assignments, read_parameter_files
from sgim_nodes.graph.processes import ProcessGroup
from sgim_nodes.graph.run_folder import (
    METADATA,
    PARAMS,
    RUNNING,
    RunFolderError,
    RunLock,
    check_resume,
    read_metadata,
    run_name_problem,
    write_metadata,
)
from sgim_nodes.graph.supervise import Interrupted, RunFailed, say
from sgim_ros import record_key
from sgim_ros.command_line import shown
from sgim_ros.params import ParameterError

ROS2RUN = REPO / "ros_ws" / "ros2run.sh"
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


def prefixes(items: Sequence[str], nodes: Sequence[NodeSpec]) -> dict[str, list[str]]:
    names = {spec.name for spec in nodes}
    found = {}
    for item in items:
        name, sep, command = item.partition("=")
        if not sep or not command.strip():
            raise ParameterError(f"--prefix expects NODE=COMMAND, got {item!r}")
        if name not in names:
            raise ParameterError(f"--prefix {item!r}: no node '{name}' in this run (its "
                                 f"nodes: {', '.join(sorted(names))})")
        try:
            found[name] = shlex.split(command)
        except ValueError as error:  # an unclosed quote
            raise ParameterError(f"--prefix {item!r}: {error}") from None
    return found


class Plan:
    """What a launch will do: the run folder, its graph, its parameters and metadata."""

    def __init__(self, run_dir: Path, learner: str, teacher: str, values: RunParameters,
                 meta: dict[str, Any], params_file: Path, log_dir: Path, lock: RunLock,
                 done: int = 0, markers: bool = True) -> None:
        self.run_dir, self.learner, self.teacher = run_dir, learner, teacher
        self.values, self.meta, self.params_file = values, meta, params_file
        self.log_dir, self.lock, self.done = log_dir, lock, done
        # The run's secret its simulator signs movements with (sgim_ros/record_key.py): made
        # with the folder, kept in it for resume and the readers ("" for a run made before).
        self.record_key = record_key.read_key(run_dir)
        self.nodes = graph(learner, teacher, markers, acts_teachers(values.shared))
        self.address_file = (Path(values.shared["address_file"])
                             if values.shared.get("address_file") else None)


def plan_new(args: argparse.Namespace) -> Plan:
    """Check everything, then make and lock the run folder."""
    files_shared, files_per_node, where = read_parameter_files(args.params_file)
    assigned, assigned_where = parse_assignments(args.param)
    stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
    name = args.name or f"{args.learner}-seed{args.seed}-{stamp}"
    if run_name_problem(name):  # parse_args refuses it; a caller's own Namespace too
        raise RunFolderError(f"run name {name!r}: {run_name_problem(name)}")
    run_dir = args.runs_dir / name
    options = RunOptions(args.learner, args.seed, args.movements, args.eval_every, args.period,
                         args.teacher, str(run_dir / "bag"), args.storage,
                         {**files_shared, **assigned}, markers=not args.no_markers,
                         wait_for_teacher=args.wait_for_teacher, web_host=args.web_host,
                         web_port=args.web_port, web_token=args.web_token,
                         web_address_file=str(run_dir / "web_teacher.url"),
                         web_linger=args.web_linger)
    values = parameters(options, files_per_node, {**where, **assigned_where})
    nodes = graph(args.learner, args.teacher, not args.no_markers,
                  acts_teachers(values.shared))
    for name in unused({**files_shared, **assigned}, nodes):
        say(f"note: parameter '{name}' is not used by a {args.learner} run "
            f"(teacher {args.teacher})")
    try:
        run_dir.mkdir(parents=True)
    except FileExistsError:
        raise RunFolderError(f"{run_dir} exists; choose another --name, or --resume it") \
            from None
    except (OSError, ValueError) as error:  # a --runs-dir that is a file, read-only, ...
        raise RunFolderError(f"cannot make the run folder {shown(run_dir)}: "
                             f"{getattr(error, 'strerror', None) or error}") from None
    lock = RunLock.take(run_dir)
    record_key.write_key(run_dir, record_key.new_key())
    meta = {
        "learner": args.learner, "seed": args.seed, "movements": args.movements,
        "teacher": values.shared["teacher"], "teacher_mode": args.teacher,
        "markers": not args.no_markers,
        "started": datetime.now(UTC).isoformat(), "outcome": RUNNING,
        "launcher_pid": os.getpid(), "parameters": masked(values.shared),
        "node_parameters": values.effective(nodes), "versions": versions(),
        "fingerprint": fingerprint(values, nodes).to_dict(),
    }
    if values.per_node:
        meta["per_node_parameters"] = {n: masked(v) for n, v in values.per_node.items()}
    return Plan(run_dir, args.learner, args.teacher, values, meta, run_dir / PARAMS,
                run_dir / "logs", lock, markers=not args.no_markers)


def plan_resume(args: argparse.Namespace) -> Plan | None:
    """Check the folder and its recordings; None when there is nothing left to do."""
    from sgim_nodes.bag.resume import next_segment, segments

    run_dir = args.resume
    meta = read_metadata(run_dir)
    lock = RunLock.take(run_dir)
    try:
        try:
            values = RunParameters.from_yaml(yaml.safe_load((run_dir / PARAMS).read_text()))
        except (OSError, yaml.YAMLError, KeyError, TypeError, AttributeError,
                ValueError) as error:  # ValueError: not UTF-8
            raise RunFolderError(f"cannot resume {run_dir}: its {PARAMS} is missing or is not "
                                 f"a parameter file written by run_experiment ({error})") \
                from None
        learner, teacher = meta["learner"], meta.get("teacher_mode") or (
            "automatic" if values.shared.get("teacher") == "automatic" else "external")
        previous_end = ""
        if meta.get("outcome") == RUNNING:
            previous_end = _recorder_trouble(run_dir)
            say(f"note: the last launcher of {run_dir} (pid {meta.get('launcher_pid', '?')}) "
                "ended without recording an outcome: "
                + (f"its disk was full ({previous_end})" if previous_end else "it was killed"))
        state = check_resume(run_dir, meta)
        if state.complete and meta.get("outcome") == "finished":
            say(f"{run_dir} already finished ({state.recorded} movements recorded); nothing "
                "to resume")
            lock.release()
            return None
        if state.lost:
            first, last = state.lost
            say(f"the recordings of {run_dir} end at movement {state.recorded}, but the run "
                f"made {state.claimed} ({METADATA}, outcome "
                f"{str(meta.get('outcome', 'unknown')).split(':')[0]}): "
                f"movements {first}..{last} were lost. The resumed run carries on from "
                f"movement {state.recorded}, where the recordings end, so they are made again")
        earlier, unknown = recorded_learner(values.shared)
        if earlier or unknown:
            kept = ", ".join(f"{k}={v}" for k, v in earlier.items())
            parts = [f"keeps what the learner did then ({kept})"] if earlier else []
            parts += [f"takes today's defaults for {', '.join(unknown)}"] if unknown else []
            names = ", ".join(sorted([*earlier, *unknown]))
            say(f"note: {run_dir} was recorded before {names} existed; the resumed run "
                f"{' and '.join(parts)}")
        segment = next_segment(run_dir)
        shared = dict(values.shared, **earlier, resume_from=str(run_dir),
                      resume_segments=len(segments(run_dir)), output=str(segment))
        values = RunParameters(check(shared), values.per_node)
        entry = {"segment": segment.name, "at": datetime.now(UTC).isoformat(),
                 "from_movement": state.recorded}
        if previous_end:  # a full disk's error, kept now that there is room again
            entry["previous_end"] = f"failed: {previous_end}"
        redone = _what_is_redone(run_dir, state.recorded)
        for line in redone:
            say(f"resume: {line}")
        if redone:
            entry["redone"] = redone
        entry.update(_fingerprint_then_and_now(run_dir, meta, values,
                                               graph(learner, teacher,
                                                     bool(meta.get("markers", True)),
                                                     acts_teachers(values.shared))))
        if state.lost:
            entry["lost_movements"] = list(state.lost)
        meta.setdefault("resumed", []).append(entry)
        meta.update(outcome=RUNNING, launcher_pid=os.getpid())
        args.learner, args.seed, args.movements = learner, meta["seed"], meta["movements"]
        args.teacher = teacher
        return Plan(run_dir, learner, teacher, values, meta, run_dir / f"params.{segment.name}"
                    ".yaml", run_dir / "logs" / segment.name, lock, done=state.recorded,
                    markers=bool(meta.get("markers", True)))
    except BaseException:
        lock.release()
        raise


def _recorder_trouble(run_dir: Path) -> str:
    """What the last segment's recorder said when it could not write (a full disk), from its
    log; '' when it said nothing of the kind (its launcher was killed)."""
    from sgim_nodes.bag.resume import segments

    parts = segments(run_dir)
    last = parts[-1].name if parts else "bag"
    log = run_dir / "logs" / ("" if last == "bag" else last) / "recorder.log"
    reason = supervise.log_reason(log)
    return reason if "could not" in reason or "space" in reason.lower() else ""


def _what_is_redone(run_dir: Path, count: int) -> list[str]:
    """The resume report (bag/resume.py): what the run stopped in the middle of."""
    import warnings

    from sgim_nodes.bag.resume import load_run_folder, what_is_redone

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the recordings' damage is said elsewhere
            return what_is_redone(load_run_folder(run_dir), count)
    except Exception as error:  # the report must not stop a resume the nodes can make
        return [f"what the run stopped in the middle of could not be read ({error})"]


def _fingerprint_then_and_now(run_dir: Path, meta: dict[str, Any], values: RunParameters,
                              nodes: list[NodeSpec]) -> dict[str, Any]:
    """The resumed segment's fingerprint, and the fields in which it differs from the run's
    first (the learner changed since: the run mixes two learners, and analyze refuses it)."""
    from sgim_nodes.provenance.fingerprint import Fingerprint

    now = fingerprint(values, nodes)
    then = Fingerprint.from_dict(meta.get("fingerprint"))
    entry: dict[str, Any] = {"fingerprint": now.value}
    if then is None:
        return entry
    changed = then.differences(now)
    if changed:
        entry["fingerprint_changed"] = changed
        say(f"note: the learner changed since {run_dir} began ({', '.join(changed)}): its "
            "resumed part is made by another learner than its first, and analyze will not "
            "pool it with unmixed runs")
    return entry


def run(args: argparse.Namespace) -> int:
    try:
        if args.resume is not None:
            refuse_full_disk(args.resume)
        plan = plan_resume(args) if args.resume is not None else plan_new(args)
        if plan is None:
            return 0
    except (RunFolderError, ParameterError) as error:
        for line in str(error).splitlines():
            say(line)
        return 2
    except DiskFull as error:
        say(f"failed: {error}")
        return 1
    except OSError as error:  # a run folder that cannot be written: one line, no traceback
        say(f"failed: {write_failure(error)}")
        return 1
    try:
        return launch(args, plan)
    except OSError as error:  # what launch writes before any node starts
        say(f"failed: {write_failure(error)}; nothing was started")
        return 1
    finally:
        plan.lock.release()


MIN_FREE_BYTES = 1 << 20
"""A resumed run needs room for its parameters, metadata and the first chunks of its bag."""


class DiskFull(RuntimeError):
    """The disk of the run folder has no room: what a full disk says, in one line."""


def write_failure(error: OSError, what: str = "") -> str:
    """An OSError as one line, with its errno's name (ENOSPC for a full disk)."""
    name = errno.errorcode.get(error.errno or 0, "")
    where = error.filename or what
    return f"cannot write {f'{where}: ' if where else ''}{error.strerror or error} " \
           f"[{name or 'error'}]"


def disk_is_full(path: Path) -> int | None:
    """The bytes free on the disk holding ``path`` when below MIN_FREE_BYTES, else None."""
    try:
        info = os.statvfs(path)
    except OSError:
        return None
    free = info.f_bavail * info.f_frsize
    return free if free < MIN_FREE_BYTES else None


def refuse_full_disk(run_dir: Path) -> None:
    free = disk_is_full(run_dir)
    if free is not None:
        raise DiskFull(f"the disk holding {run_dir} is full ({free} bytes free: No space left "
                       "on device [ENOSPC]): make room, then --resume again")


def launch(args: argparse.Namespace, plan: Plan) -> int:
    try:
        node_prefix = prefixes(args.prefix, plan.nodes)
    except ParameterError as error:
        say(str(error))
        return 2
    run_dir, meta = plan.run_dir, plan.meta
    plan.log_dir.mkdir(parents=True, exist_ok=True)
    supervise.OUT.log = open(plan.log_dir / "launcher.log", "a")  # noqa: SIM115
    supervise.stacks_on_request()
    plan.params_file.write_text(yaml.safe_dump(plan.values.to_yaml(), sort_keys=False))
    reservation = reserve_domain() if args.domain is None else None
    domain = args.domain if reservation is None else reservation.domain_id
    env = isolated_ros_environment(domain)
    os.environ.update(env)  # the launcher's own progress node joins the run's domain
    if plan.record_key:  # to the nodes only, never as a parameter (any peer can read those)
        env[record_key.ENV] = plan.record_key
    meta["ros_domain_id"] = domain
    write_metadata(run_dir, meta)
    timeout = args.timeout or default_timeout(args.movements, plan.teacher)
    say(f"{plan.learner}, seed {args.seed}, {args.movements} movements, domain {domain}, "
        f"{len(plan.nodes)} nodes, timeout {timeout:g} s -> {run_dir}")
    inherited = (plan.lock.fd, *([reservation.fd] if reservation else []))
    group = ProcessGroup(env=env, log_dir=plan.log_dir, inherited_fds=inherited)

    def start(spec: NodeSpec, log_name: str) -> subprocess.Popen:
        argv = [*node_prefix.get(spec.name, []), str(ROS2RUN), spec.package, spec.executable,
                "--ros-args", "--params-file", str(plan.params_file),
                *(["-r", f"__ns:=/{spec.namespace}"] if spec.namespace else [])]
        if spec.interactive:  # the prompt needs this terminal
            return group.start(log_name, argv, new_session=False, stdout=None, stderr=None)
        return group.start(log_name, argv)

    progress = None
    outcome, code = "failed: the launcher stopped before the run started", 1
    unwritten = ""  # why metadata.yaml could not be written at the end (a full disk)
    started = time.monotonic()
    supervisor = None
    with supervise.stop_signals() as shielded:
        try:
            # The terminal teacher's prompt shows the count itself: no bar drawn over it.
            progress = supervise.Progress(args.movements, plan.done,
                                          args.quiet or plan.teacher == "human")
            supervisor = supervise.Supervisor(plan.nodes, start, plan.log_dir, timeout,
                                              progress, address_file=plan.address_file)
            supervisor.start()
            arbiter_code = supervisor.watch()
            if arbiter_code != 0:
                why = (progress.message if progress.over else "") or supervise.log_reason(
                    supervisor.log_of(ARBITER)) or "the arbiter ended"
                raise RunFailed(f"aborted: {why} (arbiter exit code {arbiter_code}; see "
                                f"{supervisor.log_of(ARBITER)})")
            supervisor.wait_for_recorder()
            outcome, code = "finished", 0
        except Interrupted as stop:
            outcome, code = f"interrupted by {stop}", 128 + stop.signum
        except RunFailed as error:
            outcome, code = (str(error) if str(error).startswith("aborted") else
                             f"failed: {error}"), 1
        finally:
            if supervisor is not None and (code == 0 or outcome.startswith("aborted")):
                keep_page(plan, supervisor.procs.get("web_teacher"))
            with shielded(), supervise.hard_deadline(supervise.TEARDOWN_LIMIT):
                if progress is not None:
                    progress.spin(0.2)
                if supervisor is not None:  # a prompt says goodbye by itself at the end
                    supervisor.let_interactive_end(10.0 if code == 0 else 3.0)
                group.stop_all()
                group.close()
                recorder = supervisor.procs.get(RECORDER) if supervisor else None
                if code == 0 and recorder is not None and recorder.returncode != 0:
                    outcome = f"failed: {supervisor.failure(RECORDER, recorder.returncode)}"
                    code = 1
                if reservation is not None:
                    reservation.release()
                if code > 128:  # the count once the last messages are in
                    outcome += f" at movement {progress.count if progress else plan.done}"
                meta.update(ended=datetime.now(UTC).isoformat(), outcome=outcome,
                            exit_code=code, movements_done=progress.count if progress else
                            plan.done, restarts=supervisor.respawns if supervisor else {},
                            duration_s=round(time.monotonic() - started, 2))
                meta.pop("launcher_pid", None)
                meta["quarantine"] = quarantine(run_dir)
                try:
                    write_metadata(run_dir, meta)
                except OSError as error:  # a full disk: said here, kept by the next resume
                    unwritten = write_failure(error, METADATA)
    if unwritten:
        if outcome.startswith("failed") and disk_is_full(run_dir) is not None \
                and "ENOSPC" not in outcome:
            outcome += " (its disk is full: No space left on device [ENOSPC])"
        what = outcome if code else "failed: the run finished, but its end"
        say(f"{what}; and {METADATA} could not be written ({unwritten}): it still says "
            f"'{RUNNING}', which --resume reads once there is room")
        return code or 1
    say(f"{outcome}; bag and {METADATA} in {run_dir}"
        + (" (interrupted: the bag holds what was recorded; --resume carries on)"
           if code > 128 else ""))
    if progress is not None:  # last: DDS participant deletion is where a process can hang
        with supervise.stop_signals() as shielded, shielded(), \
                supervise.hard_deadline(supervise.CLOSE_LIMIT):
            progress.close()
    return code


def keep_page(plan: Plan, node: subprocess.Popen | None) -> None:
    """The run is over: before the graph stops, wait while the web teacher keeps its page for
    the person looking at it (web_teacher_node: it removes its address file once it heard the
    end, and keeps web_teacher.linger while the page stays). Ctrl-C ends the wait."""
    linger = float(plan.values.shared.get("linger", 0.0))
    address = plan.address_file
    if address is None or node is None or linger <= 0:
        return
    lingering = address.with_suffix(".linger")
    try:
        deadline = time.monotonic() + 10.0  # the node hears the end with the launcher
        while address.exists() and node.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        if lingering.exists() and node.poll() is None:
            say(f"the run is over; its page stays for at most {linger:g} s at "
                f"{lingering.read_text().strip()}: close it there, or press Ctrl-C")
            deadline = time.monotonic() + linger + 10.0
            while lingering.exists() and node.poll() is None and time.monotonic() < deadline:
                time.sleep(0.2)
    except (Interrupted, OSError):
        pass  # Ctrl-C: stop now; a file gone while read: the page has closed


def quarantine(run_dir: Path) -> dict[str, Any]:
    """The recorders' reports of records they refused, summed over the run's segments."""
    from sgim_nodes.bag.run_folder import quarantine_summary

    try:
        return quarantine_summary(run_dir)
    except Exception as error:  # the metadata is written whatever the reports hold
        return {"unreadable": str(error)}


def main(argv: Sequence[str] | None = None) -> int:
    # A parent may have blocked the stop signals (a Ray worker blocks SIGINT), and the mask
    # passes through exec to every node: they would not hear their clean shutdown.
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM, signal.SIGHUP})
    supervise.watch_owner()
    return run(parse_args(argv))


if __name__ == "__main__":
    raise SystemExit(main())
