"""Where a run or a report comes from: commit, fingerprint, versions, machine, date, time.

Every generated report starts with this block, and the freshness check reads it back, so the
block is both a table for people and a comment for the tool.
"""

from __future__ import annotations

import os
import platform
import re
import subprocess
from collections import Counter
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from sgim_nodes.provenance.fingerprint import ENVIRONMENT_FIELDS

REPO = Path(__file__).resolve().parents[3]
BEGIN, END = "<!-- provenance: begin -->", "<!-- provenance: end -->"
_DATA = re.compile(r"<!-- provenance-data: (?P<data>.*?) -->")


def git_state(repo: Path = REPO, outputs: Iterable[str] = ()) -> tuple[str, bool]:
    """(short commit, whether tracked files differ from it); ("unknown", False) outside git.
    `outputs` (paths in the repository) do not count: a report's own pages and figures, which
    it writes before it is done, are not changes of the code that made it."""
    try:
        commit = subprocess.run(["git", "-C", str(repo), "rev-parse", "--short=9", "HEAD"],
                                capture_output=True, text=True, timeout=10).stdout.strip()
        ignored = [f":(exclude){path}" for path in outputs]
        status = subprocess.run(["git", "-C", str(repo), "status", "--porcelain",
                                 "--untracked-files=no", "--", ".", *ignored],
                                capture_output=True, text=True, timeout=30).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown", False
    return (commit or "unknown"), bool(commit and status)


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> str:
    """The CPU model, cores, memory and system, in one line."""
    memory = ""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                memory = f", {int(line.split()[1]) / 2**20:.0f} GiB"
    except (OSError, ValueError, IndexError):
        pass
    return (f"{cpu_model()}, {os.cpu_count()} cores{memory}, {platform.system()} "
            f"{platform.release()}")


def made_on(machines: Iterable[str | None]) -> str:
    """The machines some runs were made on (one per run, None when not recorded), with how
    many runs each when they differ."""
    counted = Counter(machine or "a machine not recorded" for machine in machines)
    if len(counted) == 1:
        return next(iter(counted))
    return "; ".join(f"{name} ({n} runs)" for name, n in counted.most_common())


@dataclass(frozen=True)
class Provenance:
    """What made a report; ``fingerprint`` is the experiment's (experiments/pinned.py)."""

    command: str
    experiment: str
    fingerprint: str
    environment: dict[str, str]
    commit: str
    dirty: bool
    machine: str
    date: str
    wall_s: float
    cores: int
    notes: list[str] = field(default_factory=list)

    @classmethod
    def now(cls, command: str, experiment: str, fingerprint: str,
            environment: dict[str, str], wall_s: float, notes: list[str] | None = None,
            outputs: Iterable[str] = ()) -> Provenance:
        commit, dirty = git_state(outputs=outputs)
        return cls(command, experiment, fingerprint, dict(environment), commit, dirty,
                   machine(), datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
                   round(float(wall_s), 1), os.cpu_count() or 1, list(notes or []))

    def markdown(self) -> str:
        """The block: a comment the tool reads back, then a table for people."""
        import json

        env = ", ".join(f"{k} {self.environment.get(k, '?')}" for k in ENVIRONMENT_FIELDS)
        rows = [("made by", f"`{self.command}`"),
                ("commit", f"{self.commit}{' with uncommitted changes' if self.dirty else ''}"),
                ("learner fingerprint", f"`{self.fingerprint}` ({env})"),
                ("machine", self.machine), ("date", self.date),
                ("wall time", f"{_duration(self.wall_s)} on {self.cores} cores")]
        rows += [("note", note) for note in self.notes]
        table = "\n".join(f"| {k} | {v} |" for k, v in rows)
        data = json.dumps(asdict(self), sort_keys=True)
        return (f"{BEGIN}\n<!-- provenance-data: {data} -->\n| provenance | |\n|---|---|\n"
                f"{table}\n{END}")

    @classmethod
    def parse(cls, text: str) -> Provenance | None:
        """The first block of a page (None when it has none or it is unreadable)."""
        import json

        match = _DATA.search(text)
        if match is None:
            return None
        try:
            data: dict[str, Any] = json.loads(match["data"])
            return cls(**data)
        except (ValueError, TypeError):
            return None


def _duration(seconds: float) -> str:
    seconds = round(seconds)
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    if hours:
        return f"{hours} h {minutes:02d} min"
    return f"{minutes} min {secs:02d} s" if minutes else f"{secs} s"
