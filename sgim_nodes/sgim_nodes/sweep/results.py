"""The results directory of a sweep: which runs are done, and how a run gets there.

A run is made on whichever machine Ray gives it, in a scratch folder of that machine, and is
copied back to the driver as one tarball (task.py): the results directory lives on the
driver's machine only, no shared filesystem is needed, and only the driver writes into it.
A run lands there in one step: unpacked into ``.incoming/`` beside the runs, then renamed
into place, so a run folder is either absent or whole; what a dead driver leaves in
``.incoming/`` is removed when the sweep starts again.

A run is *finished* when its metadata.yaml says ``outcome: finished``, every recording of it
is complete (metadata.yaml beside the storage files, MCAP files closed with their footer)
and holds at least the movement budget on ``movements``, its parameters are the ones the
sweep asks for, and its learner fingerprint (provenance/fingerprint.py) is the one today's
checkout gives those settings. A finished run is never made again; an unfinished one is made
again from scratch (a resumed run restarts its random streams, so it is not the run an
uninterrupted one would be); a finished run of another learner (*unlike*: the code, the data,
a library or a default parameter changed since) is named with what differs and made again,
the old folder kept aside in ``.unlike/``, unless the sweep is told to keep it.
"""

from __future__ import annotations

import enum
import fcntl
import io
import os
import shutil
import tarfile
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import yaml

from sgim_nodes.bag.mcap_recovery import MAGIC
from sgim_nodes.bag.run_folder import segments
from sgim_nodes.sweep.sweep_file import RunSpec, spec_fingerprint

INCOMING = ".incoming"
UNLIKE_DIR = ".unlike"  # finished runs of another learner, moved aside before being made again
STATUS_FILE = "sweep_status.yaml"
RUN_RECORD = "sweep_run.yaml"  # in each run folder: the sweep's settings, node, attempts, times
LOCK_FILE = ".sweep.lock"
MOVEMENTS_TOPIC = "movements"


class State(enum.Enum):
    ABSENT = "absent"
    FINISHED = "finished"
    UNFINISHED = "unfinished"  # made again from scratch
    MISMATCH = "mismatch"  # a finished run of other settings: the sweep refuses to touch it
    UNLIKE = "unlike"  # a finished run of the settings, made by another learner: made again


@dataclass(frozen=True)
class RunState:
    state: State
    reason: str = ""


class ResultsBusy(RuntimeError):
    """Another sweep is writing into this results directory."""


def read_yaml(path: Path) -> Any:
    try:
        return yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError):
        return None


def write_yaml(path: Path, data: Any) -> None:
    """Write atomically: a reader sees the old file or the new one, never half of one."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(yaml.safe_dump(data, sort_keys=False))
    tmp.replace(path)


def recording_problem(run_dir: Path, movements: int) -> str | None:
    """Why the run's recordings are not complete, or None when they are."""
    parts = segments(run_dir) if run_dir.is_dir() else []
    if not parts:
        return "no recording"
    recorded = 0
    for part in parts:
        info = read_yaml(part / "metadata.yaml")
        if not isinstance(info, dict) or "rosbag2_bagfile_information" not in info:
            return f"{part.name}: no metadata.yaml (the recorder did not close it)"
        info = info["rosbag2_bagfile_information"]
        for name in info.get("relative_file_paths") or []:
            file = part / name
            if not file.is_file():
                return f"{part.name}: {name} is missing"
            if file.suffix == ".mcap" and not _mcap_closed(file):
                return f"{part.name}: {name} was not closed (no MCAP footer)"
        for topic in info.get("topics_with_message_count") or []:
            if topic["topic_metadata"]["name"].rsplit("/", 1)[-1] == MOVEMENTS_TOPIC:
                recorded += int(topic["message_count"])
    if recorded < movements:
        return f"{recorded} movements recorded, {movements} asked"
    return None


def _mcap_closed(file: Path) -> bool:
    try:
        with file.open("rb") as f:
            f.seek(-len(MAGIC), os.SEEK_END)
            return f.read() == MAGIC
    except OSError:
        return False


def settings_problem(meta: dict, spec: RunSpec) -> str | None:
    """How the run's recorded parameters differ from the spec's, or None."""
    recorded = meta.get("parameters") or {}
    differ = [f"{name}: {recorded.get(name)!r} recorded, {value!r} asked"
              for name, value in spec.expected_parameters().items()
              if recorded.get(name) != value]
    return "; ".join(differ) or None


def learner_problem(meta: dict, spec: RunSpec) -> str | None:
    """How the run's learner differs from the one today's checkout makes for the spec (the
    fingerprint's fields, and resumed parts made by another learner), or None."""
    from sgim_nodes.provenance.fingerprint import Fingerprint

    recorded = Fingerprint.from_dict(meta.get("fingerprint"))
    if recorded is None:
        return "made before learner fingerprints were recorded"
    differ = recorded.differences(spec_fingerprint(spec))
    changed = [entry["segment"] for entry in meta.get("resumed") or []
               if isinstance(entry, dict) and entry.get("fingerprint_changed")]
    if changed:
        differ.append(f"resumed by another learner ({', '.join(changed)})")
    return ", ".join(differ) or None


def run_state(run_dir: Path, spec: RunSpec) -> RunState:
    if not run_dir.exists():
        return RunState(State.ABSENT)
    meta = read_yaml(run_dir / "metadata.yaml")
    if not isinstance(meta, dict):
        return RunState(State.UNFINISHED, "no metadata.yaml")
    if meta.get("outcome") != "finished":
        return RunState(State.UNFINISHED, f"outcome: {meta.get('outcome', 'none yet')}")
    differ = settings_problem(meta, spec)
    if differ:
        return RunState(State.MISMATCH, differ)
    unlike = learner_problem(meta, spec)
    if unlike:
        return RunState(State.UNLIKE, f"its learner differs from this checkout's: {unlike}")
    problem = recording_problem(run_dir, spec.movements)
    if problem:
        return RunState(State.UNFINISHED, problem)
    return RunState(State.FINISHED)


def set_aside(runs_dir: Path, name: str) -> Path:
    """Move a finished run of another learner out of the way, keeping it: .unlike/<name>.N."""
    aside = runs_dir / UNLIKE_DIR
    aside.mkdir(parents=True, exist_ok=True)
    number = 1
    while (aside / f"{name}.{number}").exists():
        number += 1
    target = aside / f"{name}.{number}"
    (runs_dir / name).rename(target)
    return target


def lock_results(runs_dir: Path) -> IO[str]:
    """Hold the results directory for this sweep (released when the process ends)."""
    runs_dir.mkdir(parents=True, exist_ok=True)
    handle = (runs_dir / LOCK_FILE).open("a+")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.seek(0)
        holder = handle.read().strip() or "another process"
        handle.close()
        raise ResultsBusy(f"another sweep is writing into {runs_dir} ({holder})") from None
    handle.truncate(0)
    handle.write(f"pid {os.getpid()} on {os.uname().nodename}\n")
    handle.flush()
    return handle


def clean_incoming(runs_dir: Path) -> None:
    """Remove what an interrupted driver left half-installed."""
    shutil.rmtree(runs_dir / INCOMING, ignore_errors=True)


def _check_members(members: list[tarfile.TarInfo], name: str) -> None:
    for m in members:
        parts = Path(m.name).parts
        if not parts or parts[0] != name or ".." in parts or Path(m.name).is_absolute():
            raise ValueError(f"the archive of {name} holds {m.name!r}, outside its run folder")
        if not (m.isfile() or m.isdir()):
            raise ValueError(f"the archive of {name} holds {m.name!r}, not a file or folder")


def install(runs_dir: Path, spec: RunSpec, archive: bytes, record: dict[str, Any]) -> Path:
    """Put a run copied back from a worker into the results directory, in one rename.

    An unfinished folder of the same run is replaced; a finished one is kept (the run was
    done meanwhile by someone else) and the copy is dropped: a run is counted once."""
    incoming = runs_dir / INCOMING
    incoming.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f"{spec.name}.", dir=incoming))
    target = runs_dir / spec.name
    try:
        with tarfile.open(fileobj=io.BytesIO(archive), mode="r:*") as tar:
            members = tar.getmembers()
            _check_members(members, spec.name)
            # The "data" filter (Python 3.11.4 and later; Debian 12 has 3.11.2) also drops
            # modes and owners; the members are checked above either way.
            safe = {"filter": "data"} if hasattr(tarfile, "data_filter") else {}
            tar.extractall(work, members=members, **safe)
        arrived = work / spec.name
        write_yaml(arrived / RUN_RECORD, record)
        if target.exists():
            if run_state(target, spec).state is State.FINISHED:
                return target
            target.rename(work / f"{spec.name}.replaced")
        arrived.rename(target)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return target
