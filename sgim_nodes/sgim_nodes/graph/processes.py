"""Start node processes and make sure none outlives its owner.

rclpy processes can hang on SIGTERM, and a process left behind keeps publishing into the next
run. Each child gets its own process group; stopping sends SIGINT (rclpy's clean shutdown),
then SIGTERM, then SIGKILL to the whole group, each after a bounded wait.

The owner may also die without stopping them (SIGKILL, a crash). Every child therefore gets
the read end of a pipe whose write end only the owner holds, named by SGIM_LAUNCHER_FD: nodes
(sgim_ros.entry.follow_launcher) arm a parent-death signal and watch the pipe, so they end when
their owner ends, however. Children also inherit `inherited_fds` (the run's domain reservation
and folder lock), so those stay held for as long as any child lives.
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

from sgim_ros.ends import EndsReader

LAUNCHER_FD = "SGIM_LAUNCHER_FD"  # sgim_ros.entry reads it


@dataclass
class ProcessGroup:
    """The children of one graph; a context manager that always stops them all."""

    env: dict[str, str] | None = None
    log_dir: Path | None = None
    children: list[subprocess.Popen] = field(default_factory=list)
    inherited_fds: tuple[int, ...] = ()
    _lifeline: tuple[int, int] | None = field(default=None, repr=False)
    _leaders: set[int] = field(default_factory=set, repr=False)  # children leading a group

    def start(self, name: str, argv: Sequence[str], new_session: bool = True,
              extra_fds: Sequence[int] = (), **popen_kwargs) -> subprocess.Popen:
        """Start argv (in a new session unless told otherwise: a terminal program stays in the
        terminal's); its output goes to log_dir/name.log when log_dir is set; `extra_fds` are
        inherited too (a composed process's ends pipe)."""
        if self.log_dir is not None and "stdout" not in popen_kwargs:
            path = self.log_dir / f"{name}.log"  # a namespaced node's in a folder of its own
            path.parent.mkdir(parents=True, exist_ok=True)
            log = open(path, "ab")  # noqa: SIM115 - owned by the child; a respawn appends
            popen_kwargs.setdefault("stdout", log)
            popen_kwargs.setdefault("stderr", subprocess.STDOUT)
        if self._lifeline is None:
            self._lifeline = os.pipe()  # both ends close-on-exec: children get the read end
        env = dict(os.environ if self.env is None else self.env)
        env[LAUNCHER_FD] = str(self._lifeline[0])
        child = subprocess.Popen(list(argv), env=env, start_new_session=new_session,
                                 pass_fds=(self._lifeline[0], *self.inherited_fds,
                                           *extra_fds),
                                 **popen_kwargs)
        self.children.append(child)
        if new_session:
            self._leaders.add(child.pid)
        return child

    def stop_all(self, grace: float = 5.0) -> list[int]:
        """Stop every child, gently first; return their exit codes."""
        for sig, wait in ((signal.SIGINT, grace), (signal.SIGTERM, grace), (signal.SIGKILL, grace)):
            alive = [c for c in self.children if c.poll() is None]
            if not alive:
                break
            for child in alive:
                _signal(child, sig, child.pid in self._leaders)
            for child in alive:
                with contextlib.suppress(subprocess.TimeoutExpired):
                    child.wait(timeout=wait)
        # A child may have exited while its own children live on: clean the groups too.
        leaders = [c for c in self.children if c.pid in self._leaders]
        for child in leaders:
            _signal(child, signal.SIGKILL, True)
        deadline = time.monotonic() + grace
        while time.monotonic() < deadline and not all(group_is_empty(c.pid) for c in leaders):
            time.sleep(0.02)
        return [c.returncode for c in self.children]

    def close(self) -> None:
        """Close the lifeline: children still alive learn that their owner is gone."""
        if self._lifeline is not None:
            for fd in self._lifeline:
                with contextlib.suppress(OSError):
                    os.close(fd)
            self._lifeline = None

    def __enter__(self) -> ProcessGroup:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop_all()
        self.close()


def _signal(child: subprocess.Popen, sig: int, whole_group: bool) -> None:
    """Signal the child's process group (it leads its own), or the child alone."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        if whole_group:
            os.killpg(child.pid, sig)
        elif child.poll() is None:
            child.send_signal(sig)


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


def run_node_pids(run_dir: Path) -> list[int]:
    """Live processes started for the run in ``run_dir``: their command line names a parameter
    file in it (Linux /proc); zombies are dead and not listed, as in group_members. For tests
    and benchmarks that check no node outlives its launcher, whatever group it ended in."""
    found = []
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            text = cmdline.read_bytes().replace(b"\0", b" ").decode(errors="replace")
            state = (cmdline.parent / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue
        if str(run_dir) in text and "--params-file" in text and state not in ("Z", "X"):
            found.append(int(cmdline.parent.name))
    return found


def group_is_empty(pgid: int) -> bool:
    """True when no live process of the group is left."""
    return not group_members(pgid)


@dataclass
class HostedNode:
    """A node in a process that hosts several (sgim_ros/host.py), seen as if it were its own
    process: its exit code is the one its process told on the ends pipe once it has ended,
    else its process's own once that has ended (negative: a signal), else None."""

    process: subprocess.Popen
    name: str
    ends: EndsReader
    _code: int | None = field(default=None, repr=False)

    @property
    def pid(self) -> int:
        return self.process.pid

    @property
    def returncode(self) -> int | None:
        return self.poll()

    def poll(self) -> int | None:
        if self._code is None:
            code = self.ends.read().get(self.name)
            if code is None and self.process.poll() is not None:  # its end may be in by now
                code = self.ends.read().get(self.name, self.process.returncode)
            self._code = code
        return self._code

    def wait(self, timeout: float | None = None) -> int:
        deadline = None if timeout is None else time.monotonic() + timeout
        while (code := self.poll()) is None:
            if deadline is not None and time.monotonic() >= deadline:
                raise subprocess.TimeoutExpired(self.name, timeout or 0.0)
            time.sleep(0.05)
        return code

    @property
    def killed_with_it(self) -> bool:
        """True when the node ended because its whole process did, not by itself."""
        return self.poll() is not None and self.name not in self.ends.read()


NODES_SUFFIX = ".nodes"
"""logs/PROCESS.nodes: the nodes a composed process hosts, one per line (its log holds theirs)."""


def write_members(log_dir: Path, log_name: str, nodes: Sequence[str]) -> None:
    path = log_dir / f"{log_name}{NODES_SUFFIX}"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(f"{node}\n" for node in nodes), encoding="utf-8")


def node_log(log_dir: Path, node: str) -> Path:
    """The log a node of a run wrote to: logs/NODE.log when it ran alone, else the log of the
    process that hosted it (its latest start); logs/NODE.log when neither is there."""
    own = log_dir / f"{node}.log"
    if own.exists():
        return own
    hosts = [index for index in sorted(log_dir.glob(f"*{NODES_SUFFIX}"))
             if node in index.read_text(encoding="utf-8", errors="replace").split()]
    if not hosts:
        return own
    latest = max(hosts, key=lambda index: index.stat().st_mtime_ns)
    return latest.with_suffix(".log")
