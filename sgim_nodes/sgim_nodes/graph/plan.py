"""What a launch will do, decided before any node starts: a new run's folder made and locked,
or a run folder resumed from its recordings; its graph, its parameters and the metadata
written beside its bag (graph/experiment.py then starts the nodes).
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import yaml

from sgim_nodes.core.config import recorded_learner
from sgim_nodes.graph.description import (
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
from sgim_nodes.graph.experiment_options import REPO
from sgim_nodes.graph.overrides import parse_assignments, read_parameter_files
from sgim_nodes.graph.processes import node_log
from sgim_nodes.graph.run_folder import (
    METADATA,
    PARAMS,
    RUNNING,
    RunFolderError,
    RunLock,
    check_resume,
    read_metadata,
    run_name_problem,
)
from sgim_nodes.graph.supervise import say
from sgim_nodes.graph.supervisor import log_reason
from sgim_ros import record_key
from sgim_ros.command_line import shown


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
    options = RunOptions(args.learner, args.seed, args.movements, args.eval_every,
                         args.demonstration_period, args.teacher, str(run_dir / "bag"),
                         args.storage, {**files_shared, **assigned}, markers=not args.no_markers,
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
                f"made {state.claimed} (its launcher said so; outcome "
                f"{str(meta.get('outcome', 'unknown')).split(':')[0]}): "
                f"movements {first}..{last} were lost. The resumed run carries on from "
                f"movement {state.recorded}, where the recordings end, so they are made again")
        cut = [part.name for part in segments(run_dir) if not (part / METADATA).exists()]
        if cut:
            say(f"note: {', '.join(cut)} of {run_dir} ended without their rosbag2 {METADATA}: "
                "this project's readers read them, and `ros_ws/ros2run.sh sgim_nodes repair "
                f"{run_dir}` makes them whole for rosbags, ros2 bag and Foxglove")
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
        redone = _what_is_redone(run_dir, state.recorded, values.shared, int(meta["movements"]))
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
        if cut:
            entry["cut_recordings"] = cut
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
    log = node_log(run_dir / "logs" / ("" if last == "bag" else last), "recorder")
    reason = log_reason(log)
    return reason if "could not" in reason or "space" in reason.lower() else ""


def _what_is_redone(run_dir: Path, count: int, shared: dict[str, Any], budget: int) -> list[str]:
    """The resume report (bag/resume.py): what the run stopped in the middle of."""
    import warnings

    from sgim_nodes.bag.resume import load_run_folder, what_is_redone

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the recordings' damage is said elsewhere
            return what_is_redone(load_run_folder(run_dir), count,
                                  int(shared.get("imitation_count") or 0), budget)
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
