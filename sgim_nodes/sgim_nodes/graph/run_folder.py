"""A run folder: its lock, its metadata.yaml, and what its recording says about a resume.

    runs/<name>/
        .lock          held (flock) by the launcher and every node of the run while they live
        .made          the movements the last segment made, written in place (CLAIM)
        metadata.yaml  learner, seed, budget, parameters, versions, timing, outcome
        params.yaml    the ROS parameter file every node was started with
        bag/, bag.resumeN/, logs/

The lock stops two launchers, two resumes of one run for instance, from writing into the same
folder; it is an flock, so the system frees it when its last holder dies, killed or not.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from sgim_nodes.core.learner_registry import is_learner, learner_names
from sgim_ros.command_line import YamlProblem, parse_yaml
from sgim_ros.params import SEED_MAX, seed_problem

LOCK_NAME = ".lock"
METADATA = "metadata.yaml"
PARAMS = "params.yaml"
RUNNING = "running"  # the outcome while a launcher works; left as is if the launcher is killed
CLAIM = ".made"
CLAIM_SIZE = 64
"""The claim file: '<segment> <movements made>', padded to CLAIM_SIZE bytes when the launch
has room and overwritten in place at its end, so that it is written even on a disk that has
filled since, where metadata.yaml cannot be: a resume then knows which movements were lost."""


NAME_MAX = 255  # bytes of one path component (Linux, most file systems)


class RunFolderError(Exception):
    """The run folder cannot be used as asked; the message says why and what to do."""


def run_name_problem(name: str) -> str | None:
    """Why `name` cannot be a run folder's name inside the runs directory, or None.

    A name is one path component: with a '/' or as '..' it would put the run (and whatever
    the launcher writes there) outside --runs-dir; a NUL or a character that does not print
    would break the one-line messages that name the folder."""
    if not name or name in (".", ".."):
        return "a run's name must be a folder name, not empty, '.' or '..'"
    if "/" in name:
        return "a run's name is one folder inside --runs-dir: no '/'"
    if not name.isprintable():
        return "a run's name holds printable characters only (no NUL, newline or tab)"
    if len(name.encode("utf-8", "surrogateescape")) > NAME_MAX:
        return f"a run's name has at most {NAME_MAX} bytes"
    return None


@dataclass
class RunLock:
    """An exclusive lock on a run folder, held while this object (or a child process that
    inherited `fd`) lives."""

    path: Path
    fd: int

    @classmethod
    def take(cls, run_dir: Path) -> RunLock:
        path = run_dir / LOCK_NAME
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 64).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise RunFolderError(
                f"{run_dir} is in use by another launcher (pid {holder}) or by nodes it "
                "started: wait until it ends, or stop it") from None
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        return cls(path, fd)

    def release(self) -> None:
        with contextlib.suppress(OSError):
            os.close(self.fd)


def write_metadata(run_dir: Path, meta: dict[str, Any]) -> None:
    """Atomically: a reader never sees half a file, a crash leaves the old one."""
    tmp = run_dir / f".{METADATA}.tmp"
    tmp.write_text(yaml.safe_dump(meta, sort_keys=False))
    os.replace(tmp, run_dir / METADATA)


def read_metadata(run_dir: Path) -> dict[str, Any]:
    """The metadata of a run to resume, checked: RunFolderError names what is missing."""
    path = run_dir / METADATA
    if not run_dir.is_dir():
        raise RunFolderError(f"{run_dir} is not a folder")
    try:
        meta = parse_yaml(path.read_bytes())
    except OSError as error:
        raise RunFolderError(f"{run_dir} is not a run folder: cannot read {METADATA} "
                             f"({error.strerror})") from None
    except YamlProblem as problem:  # binary, not YAML, a key twice: one line, no traceback
        raise RunFolderError(f"{path}: {problem}") from None
    if not isinstance(meta, dict):
        raise RunFolderError(f"{path} must be a mapping (learner: ..., seed: ..., "
                             f"movements: ...), it holds a {type(meta).__name__}")
    problems = []
    hint = _params_hint(run_dir)
    for key, valid, what in (
            ("learner", is_learner, f"one of {', '.join(learner_names(plugins=False))} or "
             "another package's (core/learner_registry.py)"),
            ("seed", lambda v: seed_problem(v) is None, f"an integer in 0..{SEED_MAX}"),
            ("movements", lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 1,
             "an integer >= 1")):
        if key not in meta:
            problems.append(f"has no '{key}' ({what})"
                            + (f"; {PARAMS} says {key}: {hint[key]}" if key in hint else ""))
        elif not valid(meta[key]):
            problems.append(f"'{key}' must be {what}, got {repr(meta[key])[:60]}")
    if problems:
        raise RunFolderError(f"cannot resume {run_dir}: {path.name} " + "; ".join(problems)
                             + f". Fix {path} and resume again.")
    return meta


def _params_hint(run_dir: Path) -> dict[str, Any]:
    try:
        data = yaml.safe_load((run_dir / PARAMS).read_text())
        return dict(data["/**"]["ros__parameters"])
    except (OSError, yaml.YAMLError, KeyError, TypeError, ValueError):
        return {}


def recorded_count(run_dir: Path) -> int:
    """The last movement index the run's recordings hold (0 when none)."""
    from sgim_nodes.bag.resume import load_run_folder, segments

    if not segments(run_dir):
        return 0  # the launcher stopped before the recorder made its bag
    try:
        records = load_run_folder(run_dir)
    except Exception as error:  # a reader's refusal: say it in one line
        raise RunFolderError(f"cannot read the recordings of {run_dir}: {error}") from None
    return max((m.index for m in records.movements), default=0)


def write_claim(run_dir: Path, segment: str, count: int) -> str:
    """Say in the claim file that ``segment`` made ``count`` movements, in place (no new block
    on a full disk once the file exists); '' or why it could not."""
    text = f"{segment} {int(count)}".encode().ljust(CLAIM_SIZE)[:CLAIM_SIZE]
    try:
        fd = os.open(run_dir / CLAIM, os.O_WRONLY | os.O_CREAT, 0o644)
        try:
            os.pwrite(fd, text, 0)
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError as error:
        return error.strerror or str(error)
    return ""


def read_claim(run_dir: Path) -> tuple[str, int] | None:
    """(segment, movements it made) from the claim file, or None (absent or malformed)."""
    try:
        segment, count = (run_dir / CLAIM).read_bytes().decode().split()
        return segment, int(count)
    except (OSError, UnicodeDecodeError, ValueError):
        return None


@dataclass
class ResumeCheck:
    """What the recordings say before a resume: whether there is anything to do, and what
    was lost (movements the run made but its bag does not hold)."""

    recorded: int
    claimed: int
    budget: int

    @property
    def lost(self) -> tuple[int, int] | None:
        return (self.recorded + 1, self.claimed) if self.claimed > self.recorded else None

    @property
    def complete(self) -> bool:
        return self.recorded >= self.budget


def check_resume(run_dir: Path, meta: dict[str, Any]) -> ResumeCheck:
    """Compare the recordings with what metadata.yaml, or the claim file of the last segment
    (when metadata.yaml could not be written), says the run did."""
    from sgim_nodes.bag.run_folder import segments

    claimed = meta.get("movements_done", 0)
    if not isinstance(claimed, int) or isinstance(claimed, bool):
        claimed = 0
    if meta.get("outcome") == "finished":
        claimed = max(claimed, meta["movements"])
    claim, parts = read_claim(run_dir), segments(run_dir)
    if claim is not None and parts and claim[0] == parts[-1].name:
        claimed = max(claimed, claim[1])
    return ResumeCheck(recorded_count(run_dir), claimed, meta["movements"])
