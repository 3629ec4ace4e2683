"""Start node processes and make sure none outlives its owner.

rclpy processes can hang on SIGTERM, and a process left behind keeps publishing into the next
run. Each child gets its own process group; stopping sends SIGINT (rclpy's clean shutdown),
then SIGTERM, then SIGKILL to the whole group, each after a bounded wait.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class ProcessGroup:
    """The children of one graph; a context manager that always stops them all."""

    env: dict[str, str] | None = None
    log_dir: Path | None = None
    children: list[subprocess.Popen] = field(default_factory=list)

    def start(self, name: str, argv: Sequence[str], **popen_kwargs) -> subprocess.Popen:
        """Start argv in a new session; its output goes to log_dir/name.log when log_dir is set."""
        if self.log_dir is not None and "stdout" not in popen_kwargs:
            self.log_dir.mkdir(parents=True, exist_ok=True)
            log = open(self.log_dir / f"{name}.log", "wb")  # noqa: SIM115 - owned by the child
            popen_kwargs.setdefault("stdout", log)
            popen_kwargs.setdefault("stderr", subprocess.STDOUT)
        child = subprocess.Popen(list(argv), env=self.env, start_new_session=True, **popen_kwargs)
        self.children.append(child)
        return child

    def stop_all(self, grace: float = 5.0) -> list[int]:
        """Stop every child, gently first; return their exit codes."""
        for sig, wait in ((signal.SIGINT, grace), (signal.SIGTERM, grace), (signal.SIGKILL, grace)):
            alive = [c for c in self.children if c.poll() is None]
            if not alive:
                break
            for child in alive:
                _signal_group(child, sig)
            for child in alive:
                with contextlib.suppress(subprocess.TimeoutExpired):
                    child.wait(timeout=wait)
        # A child may have exited while its own children live on: clean the groups too.
        for child in self.children:
            _signal_group(child, signal.SIGKILL)
        deadline = time.monotonic() + grace
        while time.monotonic() < deadline and not all(group_is_empty(c.pid) for c in self.children):
            time.sleep(0.02)
        return [c.returncode for c in self.children]

    def __enter__(self) -> ProcessGroup:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop_all()


def _signal_group(child: subprocess.Popen, sig: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(child.pid, sig)


def group_members(pgid: int) -> list[int]:
    """Live processes of a process group (Linux /proc); zombies are dead and not listed.

    An orphaned zombie waits for whoever reaps orphans here (a container's PID 1 may never
    do it), yet it holds no resources and runs nothing: it is not "left behind".
    """
    members = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:
            continue
        # Fields after the command name, which is in parentheses and may hold spaces.
        fields = text[text.rindex(")") + 2 :].split()
        state, group = fields[0], int(fields[2])
        if group == pgid and state not in ("Z", "X"):
            members.append(int(stat.parent.name))
    return members


def group_is_empty(pgid: int) -> bool:
    """True when no live process of the group is left."""
    return not group_members(pgid)
