"""Watch a running graph's processes until the run ends, and say truly how it ended.

A run is finished only when the arbiter says so (exit code 0 after its FINISHED status) and
the recorder has written everything (exit code 0; the recorder exits 3 on a write error such
as a full disk). Any other node that stops before the end fails the run, the simulator
excepted (it holds no state and is restarted, at most MAX_RESPAWNS times).

Nodes may share a process (graph/process_plan.py). Each node is still watched as if it were
its own process (processes.HostedNode reads its end from its process's ends file); a process
that dies takes its nodes with it, and the run's outcome then names the process and its nodes.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from sgim_nodes.graph.description import ARBITER, MAX_RESPAWNS, RECORDER
from sgim_nodes.graph.process_plan import ProcessSpec
from sgim_nodes.graph.processes import HostedNode, write_members
from sgim_nodes.graph.supervise import Progress, RunFailed, say
from sgim_ros.ends import EndsReader

ARBITER_EXIT_WAIT = 60.0  # seconds for the arbiter to exit after its final status
# The recorder ends by itself once the movements up to the final count are in and the graph
# has been quiet (at most 30 s after the final status, nodes/recorder.py FINISH_LIMIT).
RECORDER_EXIT_WAIT = 45.0
RECORDER_WRITE_ERROR = 3  # the recorder's exit code when it cannot write the bag
ROS_LOG_PREFIX = re.compile(r"^\[[A-Z]+\] \[[\d.]+\] \[[\w/.]+\]: ")

Launch = Callable[[ProcessSpec, str, "int | None"], subprocess.Popen]
"""(process, log name, the ends pipe's write end or None for a lone node) -> the started
process, which inherits that descriptor."""


def log_reason(log: Path, limit: int = 300) -> str:
    """Why a node ended, from its log, to quote in the run's outcome: its first logged error
    (the cause; later ones tend to follow from it), else the last line that looks like one
    (a traceback's exception). DDS transport chatter is not a reason."""
    try:
        lines = [line.strip() for line in log.read_text(errors="replace").splitlines()
                 if "RTPS_" not in line]
    except OSError:
        return ""
    logged = [line for line in lines if line.startswith("[ERROR]")]
    if logged:
        return ROS_LOG_PREFIX.sub("", logged[0])[:limit]
    for line in reversed(lines):
        if any(word in line for word in ("Error", "error", "refused", "cannot")):
            return line[:limit]
    return ""


def how_it_ended(code: int) -> str:
    if code < 0:
        with_signal = signal.Signals(-code).name if -code in signal.valid_signals() else -code
        return f"was killed by {with_signal}"
    return f"exited with code {code}"


@dataclass
class Supervisor:
    """Starts the graph's processes through `launch` and watches them until the run ends."""

    processes: list[ProcessSpec]
    launch: Launch | None
    log_dir: Path
    timeout: float
    progress: Progress
    address_file: Path | None = None  # the web teacher's page address, said once it serves
    respawns: dict[str, int] = field(default_factory=dict)  # by process
    procs: dict[str, object] = field(default_factory=dict)  # by node: Popen or HostedNode

    def start(self) -> None:
        for process in self.processes:
            self._start(process)

    def _start(self, process: ProcessSpec) -> None:
        log_name = process.log_name(self.respawns.get(process.name, 0))
        if not process.composed:
            self.procs[process.members[0].name] = self.launch(process, log_name, None)
            return
        write_members(self.log_dir, log_name, [spec.name for spec in process.members])
        read_end, write_end = os.pipe()
        try:
            started = self.launch(process, log_name, write_end)
        finally:
            os.close(write_end)  # the process holds it now: its end is the pipe's end
        ends = EndsReader(read_end)
        for spec in process.members:
            self.procs[spec.name] = HostedNode(started, spec.name, ends)

    def process_of(self, node: str) -> ProcessSpec:
        for process in self.processes:
            if any(spec.name == node for spec in process.members):
                return process
        raise KeyError(node)

    def log_of(self, name: str) -> Path:
        """The log a node writes to: its process's, of its latest start."""
        process = self.process_of(name)
        return self.log_dir / f"{process.log_name(self.respawns.get(process.name, 0))}.log"

    def failure(self, name: str, code: int) -> str:
        process = self.process_of(name)
        child = self.procs.get(name)
        if process.composed and isinstance(child, HostedNode) and child.killed_with_it:
            nodes = ", ".join(spec.name for spec in process.members)
            reason = log_reason(self.log_of(name))
            return (f"process {process.name} ({nodes}) {how_it_ended(code)} at movement "
                    f"{self.progress.count}" + (f": {reason}" if reason else "")
                    + f"; see {self.log_of(name)}")
        if name == RECORDER and code == RECORDER_WRITE_ERROR:
            what = "the recorder could not write the bag"
        else:
            what = f"the {name} node stopped" if name == RECORDER else f"node {name} stopped"
        reason = log_reason(self.log_of(name))
        return (f"{what} (exit {code}) at movement {self.progress.count}"
                + (f": {reason}" if reason else "") + f"; see {self.log_of(name)}")

    def _dead_process(self) -> str | None:
        """A node of a composed process that died with it (a kill, a crash), if any."""
        for name, child in self.procs.items():
            if isinstance(child, HostedNode) and child.killed_with_it:
                return name
        return None

    def watch(self) -> int:
        """Until the arbiter ends: the arbiter's exit code. RunFailed if any other node stops
        (the simulator is restarted), a composed process dies, or the run outlives its
        timeout."""
        began = time.monotonic()
        while True:
            self.progress.spin(0.2)
            if self.address_file is not None and self.address_file.exists():
                self.progress.say(f"teach at {self.address_file.read_text().strip()}")
                self.address_file = None
            dead = self._dead_process()
            if dead is not None and not self.process_of(dead).respawn:
                raise RunFailed(self.failure(dead, self.procs[dead].poll()))
            if self.procs[ARBITER].poll() is not None or self.progress.over:
                break
            for name, child in list(self.procs.items()):
                code = child.poll()
                if code is None or name == ARBITER or self.procs.get(name) is not child:
                    continue  # running, the arbiter, or gone or restarted with its process
                process = self.process_of(name)
                if process.interactive:  # the human teacher left the prompt: the run goes on
                    say(f"{name} ended (exit {code}); the run goes on without it")
                    del self.procs[name]
                    continue
                if not process.respawn or self.respawns.get(process.name, 0) >= MAX_RESPAWNS:
                    raise RunFailed(self.failure(name, code))
                self.respawns[process.name] = self.respawns.get(process.name, 0) + 1
                said = name if not process.composed else f"process {process.name} ({name})"
                say(f"{said} stopped (exit {code}); restarting it "
                    f"({self.respawns[process.name]}/{MAX_RESPAWNS})")
                self._start(process)
            if time.monotonic() - began > self.timeout:
                raise RunFailed(f"timed out after {self.timeout:g} s (--timeout) at movement "
                                f"{self.progress.count}")
        arbiter = self.procs[ARBITER]
        try:
            arbiter.wait(timeout=ARBITER_EXIT_WAIT)
        except subprocess.TimeoutExpired:
            raise RunFailed(f"the arbiter did not exit {ARBITER_EXIT_WAIT:g} s after its "
                            f"final status; see {self.log_of(ARBITER)}") from None
        dead = self._dead_process()
        if dead is not None:  # killed with the arbiter: not the arbiter's own end
            raise RunFailed(self.failure(dead, self.procs[dead].poll()))
        self.progress.spin(0.5)  # the last status may still be on its way
        return arbiter.returncode

    def let_interactive_end(self, seconds: float) -> None:
        """Give a terminal prompt (human_input) time to leave by itself once the run is over."""
        deadline = time.monotonic() + seconds
        for name, child in self.procs.items():
            if self.process_of(name).interactive:
                while child.poll() is None and time.monotonic() < deadline:
                    time.sleep(0.1)

    def wait_for_recorder(self) -> None:
        """The recorder ends by itself once it has written the end of the run; RunFailed if it
        ends with an error."""
        recorder = self.procs[RECORDER]
        deadline = time.monotonic() + RECORDER_EXIT_WAIT
        while recorder.poll() is None and time.monotonic() < deadline:
            self.progress.spin(0.2)
        if recorder.poll() is not None and recorder.returncode != 0:
            raise RunFailed(self.failure(RECORDER, recorder.returncode))
