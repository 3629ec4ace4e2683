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
import shlex
import signal
import subprocess
import time
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import yaml

from sgim_nodes.graph import supervise
from sgim_nodes.graph.description import ARBITER, NODES, RECORDER, NodeSpec
from sgim_nodes.graph.domain import (
    DomainInUse,
    DomainReservation,
    hold_run_domain,
    isolated_ros_environment,
)
from sgim_nodes.graph.experiment_options import REPO, default_timeout, parse_args
from sgim_nodes.graph.plan import Plan, plan_new, plan_resume
from sgim_nodes.graph.process_plan import (
    DEFAULT_GROUPS,
    ProcessSpec,
    parse_groups,
    process_plan,
    unknown_in_groups,
)
from sgim_nodes.graph.processes import ProcessGroup
from sgim_nodes.graph.run_folder import (
    METADATA,
    RUNNING,
    RunFolderError,
    write_claim,
    write_metadata,
)
from sgim_nodes.graph.supervise import Interrupted, RunFailed, say
from sgim_nodes.graph.supervisor import Supervisor, log_reason
from sgim_ros import record_key
from sgim_ros.params import ParameterError

ROS2RUN = REPO / "ros_ws" / "ros2run.sh"


def prefixes(items: Sequence[str], names: Sequence[str]) -> dict[str, list[str]]:
    """--prefix NAME=COMMAND options -> the command before each named node or process."""
    found = {}
    for item in items:
        name, sep, command = item.partition("=")
        if not sep or not command.strip():
            raise ParameterError(f"--prefix expects NODE=COMMAND, got {item!r}")
        if name not in names:
            raise ParameterError(f"--prefix {item!r}: no node or process '{name}' in this run "
                                 f"(its nodes and processes: {', '.join(sorted(set(names)))})")
        try:
            found[name] = shlex.split(command)
        except ValueError as error:  # an unclosed quote
            raise ParameterError(f"--prefix {item!r}: {error}") from None
    return found


def processes_of(args: argparse.Namespace, nodes: Sequence[NodeSpec]
                 ) -> tuple[list[ProcessSpec], dict[str, list[str]]]:
    """The run's processes (a node given its own --prefix runs alone) and their prefixes."""
    groups = parse_groups(args.compose) if args.compose else None
    known = {*NODES, *(spec.name for spec in nodes)}  # this run's namespaced ones too
    unknown = unknown_in_groups(groups or {}, known)
    if unknown:
        raise ParameterError(f"--compose names no node {', '.join(unknown)} (the graph's "
                             f"nodes: {', '.join(sorted(known))})")
    names = [spec.name for spec in nodes] + list(groups or DEFAULT_GROUPS)
    prefix = prefixes(args.prefix, names)
    plan = process_plan(nodes, groups, args.separate, alone=prefix)
    return plan, prefix


def run(args: argparse.Namespace) -> int:
    try:  # before the run folder is made: a refused run leaves nothing behind
        reservation = hold_run_domain(args.domain)
    except DomainInUse as error:
        say(str(error))
        return 2
    except RuntimeError as error:  # no free domain on this host
        say(f"failed: {error}")
        return 1
    try:
        return plan_and_launch(args, reservation)
    finally:
        reservation.release()


def plan_and_launch(args: argparse.Namespace, reservation: DomainReservation) -> int:
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
        return launch(args, plan, reservation)
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


def launch(args: argparse.Namespace, plan: Plan, reservation: DomainReservation) -> int:
    try:
        processes, prefix = processes_of(args, plan.nodes)
    except ParameterError as error:
        say(str(error))
        return 2
    run_dir, meta = plan.run_dir, plan.meta
    plan.log_dir.mkdir(parents=True, exist_ok=True)
    supervise.OUT.log = open(plan.log_dir / "launcher.log", "a")  # noqa: SIM115
    supervise.stacks_on_request()
    plan.params_file.write_text(yaml.safe_dump(plan.values.to_yaml(), sort_keys=False))
    domain = reservation.domain_id
    env = isolated_ros_environment(domain)
    os.environ.update(env)  # the launcher's own progress node joins the run's domain
    if plan.record_key:  # to the nodes only, never as a parameter (any peer can read those)
        env[record_key.ENV] = plan.record_key
    meta["ros_domain_id"] = domain
    write_metadata(run_dir, meta)
    segment = Path(plan.values.shared["output"]).name
    write_claim(run_dir, segment, plan.done)  # its room taken now, while there is some
    timeout = args.timeout or default_timeout(args.movements, plan.teacher)
    say(f"{plan.learner}, seed {args.seed}, {args.movements} movements, domain {domain}, "
        f"{len(plan.nodes)} nodes in {len(processes)} processes, timeout {timeout:g} s -> "
        f"{run_dir}")
    inherited = (plan.lock.fd, *reservation.fds)
    group = ProcessGroup(env=env, log_dir=plan.log_dir, inherited_fds=inherited)

    def start(process: ProcessSpec, log_name: str, ends_fd: int | None) -> subprocess.Popen:
        ros_args = ["--ros-args", "--params-file", str(plan.params_file)]
        if process.composed:
            argv = [*prefix.get(process.name, []), str(ROS2RUN), "sgim_nodes", "composed",
                    "--process", process.name, "--ends-fd", str(ends_fd),
                    *process.node_options(), *ros_args]
            return group.start(log_name, argv, extra_fds=(ends_fd,))
        spec = process.members[0]
        argv = [*prefix.get(spec.name, []), str(ROS2RUN), spec.package, spec.executable,
                *ros_args, *(["-r", f"__ns:=/{spec.namespace}"] if spec.namespace else [])]
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
            supervisor = Supervisor(processes, start, plan.log_dir, timeout,
                                              progress, address_file=plan.address_file)
            supervisor.start()
            arbiter_code = supervisor.watch()
            if arbiter_code != 0:
                why = (progress.message if progress.over else "") or log_reason(
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
                reservation.release()
                if code > 128:  # the count once the last messages are in
                    outcome += f" at movement {progress.count if progress else plan.done}"
                meta.update(ended=datetime.now(UTC).isoformat(), outcome=outcome,
                            exit_code=code, movements_done=progress.count if progress else
                            plan.done, restarts=supervisor.respawns if supervisor else {},
                            duration_s=round(time.monotonic() - started, 2))
                meta.pop("launcher_pid", None)
                meta["quarantine"] = quarantine(run_dir)
                write_claim(run_dir, segment, meta["movements_done"])
                try:
                    write_metadata(run_dir, meta)
                except OSError as error:  # a full disk: said here, kept by the next resume
                    unwritten = write_failure(error, METADATA)
                if progress is not None:  # the outcome below goes after the bar, not on it
                    progress.end_bar()
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
        # (seen once under load, 20 s in the /parameter_events writer's deletion); the run is
        # recorded by now, so a hang there leaves its stacks and the run's own exit code.
        with supervise.stop_signals() as shielded, shielded(), \
                supervise.hard_deadline(supervise.CLOSE_LIMIT, exit_code=code):
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
