"""The launcher's side of a running graph: its progress, its signals and its output.

Every wait is bounded (graph/supervisor.py watches the nodes): the run's --timeout, the
arbiter's exit after its last status, the recorder's end, and the launcher's own teardown
(`hard_deadline`: past it, every thread's stack goes to launcher.log and the launcher exits
with 1, or with the run's own code once the run is recorded; `kill -USR1` a launcher to get
those stacks at any time).

The launcher's own output goes to the terminal and to logs/launcher.log; a terminal pipe that
breaks (`run_experiment.sh ... | tee log`, then Ctrl-C, which also ends tee) is noticed once
and then ignored, so stopping the nodes never fails half-way.
"""

from __future__ import annotations

import contextlib
import faulthandler
import os
import signal
import sys
import threading
import time
from typing import TextIO

from sgim_nodes.graph.exit_timer import exit_later as _exit_later

# The teardown: a prompt's goodbye (<= 10 s), stop_all (<= 20 s), the metadata (well under 1 s).
TEARDOWN_LIMIT = 90.0
CLOSE_LIMIT = 20.0  # the launcher's own rclpy node and context (DDS participant deletion)


class RunFailed(RuntimeError):
    """The run cannot be reported finished; the message says why."""


class Interrupted(BaseException):
    """A signal asked the launcher to stop (SIGINT, SIGTERM, SIGHUP)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


class SafeStream:
    """A text stream for the launcher's messages: a write to a closed pipe is dropped (once
    noticed, the descriptor is pointed at /dev/null, so that nothing later fails either),
    and every line also goes to the run's launcher.log when one is open."""

    def __init__(self, stream: TextIO | None = None) -> None:
        self._stream = stream  # None: whatever sys.stderr is when writing
        self.broken = False
        self.log: TextIO | None = None

    @property
    def stream(self) -> TextIO:
        return sys.stderr if self._stream is None else self._stream

    def write(self, text: str) -> int:
        if self.log is not None:
            with contextlib.suppress(OSError, ValueError):
                self.log.write(text.replace("\r", "\n"))
                self.log.flush()
        if not self.broken:
            try:
                self.stream.write(text)
                self.stream.flush()
            except (BrokenPipeError, OSError, ValueError):
                self._break()
        return len(text)

    def flush(self) -> None:
        if not self.broken:
            try:
                self.stream.flush()
            except (BrokenPipeError, OSError, ValueError):
                self._break()

    def _break(self) -> None:
        self.broken = True
        with contextlib.suppress(OSError, ValueError, AttributeError):
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self.stream.fileno())
            os.close(devnull)

    def isatty(self) -> bool:
        return not self.broken and self.stream.isatty()

    def fileno(self) -> int:
        return self.stream.fileno()


OUT = SafeStream()
_BAR: list = []  # the progress bar being drawn, if any: say() writes above it


def say(message: str) -> None:
    """A line of the launcher's. While the progress bar is drawn, the line goes above it:
    written after the bar's last carriage return, it would share the bar's line and be drawn
    over by its next refresh."""
    line = f"run_experiment: {message}"
    if _BAR:
        with contextlib.suppress(Exception):
            _BAR[-1].write(line, file=OUT)
            return
    OUT.write(line + "\n")


def _stack_file() -> TextIO:
    return OUT.log if OUT.log is not None else sys.__stderr__


def stacks_on_request(signum: int = signal.SIGUSR1) -> None:
    """`kill -USR1 <launcher>` writes every thread's stack to launcher.log (else stderr) and
    the run goes on: how to see where a launcher that seems stuck is."""
    faulthandler.register(signum, file=_stack_file(), all_threads=True, chain=False)


@contextlib.contextmanager
def hard_deadline(seconds: float, exit_code: int = 1):
    """The last resort for a block that must end: if it is still running after `seconds`,
    every thread's stack goes to launcher.log (else stderr) and the process exits with
    `exit_code` (the run's own, when only the launcher's goodbye to DDS is left). Both are
    done by C threads (faulthandler's watchdog, a timer of the C library), so they fire even
    when a thread hangs in C code holding the GIL (an rclpy or DDS call), where no Python
    timer could run."""
    stream = _stack_file()
    with contextlib.suppress(OSError, ValueError):
        stream.flush()
    try:
        disarm = _exit_later(seconds + STACKS_MARGIN, exit_code)
        faulthandler.dump_traceback_later(seconds, exit=False, file=stream)
    except (OSError, AttributeError):  # no POSIX timers here: faulthandler exits, with 1
        disarm = _nothing
        faulthandler.dump_traceback_later(seconds, exit=True, file=stream)
    try:
        yield
    finally:
        disarm()
        faulthandler.cancel_dump_traceback_later()


STACKS_MARGIN = 0.5  # seconds between the stacks written and the exit


def _nothing() -> None:
    pass


@contextlib.contextmanager
def stop_signals():
    """SIGINT, SIGTERM and SIGHUP (a closed terminal) raise Interrupted; inside `shielded()`
    they are only noted, so that stopping the nodes is never cut short."""
    state = {"shielded": False, "pending": None}

    def handler(signum, _frame):
        if state["shielded"]:
            state["pending"] = signum
            say(f"{signal.Signals(signum).name} received: already stopping, please wait")
            return
        raise Interrupted(signum)

    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM,
                                                        signal.SIGHUP)}

    @contextlib.contextmanager
    def shielded():
        state["shielded"] = True
        try:
            yield
        finally:
            state["shielded"] = False

    try:
        yield shielded
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def watch_owner(fd_variable: str = "SGIM_LAUNCHER_FD") -> None:
    """If a program that watches over this launcher (run_study, a test) gave it a lifeline,
    stop the run as on SIGTERM when that program dies, however it dies."""
    try:
        fd = int(os.environ.get(fd_variable, ""))
        os.fstat(fd)
    except (ValueError, OSError):
        return
    os.environ.pop(fd_variable, None)

    def watch() -> None:
        while True:
            try:
                if not os.read(fd, 64):
                    break
            except InterruptedError:
                continue
            except OSError:
                break
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=watch, name="owner-watchdog", daemon=True).start()


class Progress:
    """Follows run_status and the movements with a small rclpy node of the launcher's own:
    the arbiter's state and message, and the highest movement index seen, a witness of what
    the run did that is independent of the recorder."""

    def __init__(self, total: int, done: int, quiet: bool) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from tqdm import tqdm

        from sgim_msgs.msg import Movement, RunStatus
        from sgim_ros import qos

        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, signal_handler_options=_no_rclpy_signal_handlers())
        self.node = Node("experiment_launcher", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.state: int | None = None
        self.message = ""
        self.status_count = done
        self.seen = done
        self.bar = tqdm(total=total, initial=done, disable=quiet, unit="mv", file=OUT,
                        dynamic_ncols=True)
        if not quiet:
            _BAR.append(self.bar)
        self.node.create_subscription(RunStatus, "run_status", self._on_status, qos.RECORDS)
        self.node.create_subscription(Movement, "movements", self._on_movement, qos.RECORDS)
        self.finished_state = (RunStatus.STATE_FINISHED, RunStatus.STATE_ABORTED)

    def _on_status(self, msg) -> None:
        self.status_count = max(self.status_count, msg.movement_index)
        self.state, self.message = msg.state, msg.message
        self._show()

    def _on_movement(self, msg) -> None:
        if msg.process != msg.PROCESS_EVALUATION:
            self.seen = max(self.seen, int(msg.index))
            self._show()

    def _show(self) -> None:
        self.bar.update(max(0, max(self.seen, self.status_count) - self.bar.n))

    @property
    def count(self) -> int:
        return max(self.seen, self.status_count)

    def say(self, text: str) -> None:
        """A line of the launcher's, above the progress bar."""
        say(text)

    def end_bar(self) -> None:
        """Draw the bar a last time and end its line, so that what follows (the run's
        outcome) is on lines of its own, after it, and nothing draws over them."""
        if self.bar in _BAR:
            _BAR.remove(self.bar)
        with contextlib.suppress(Exception):
            self.bar.close()

    def spin(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.05)

    @property
    def over(self) -> bool:
        return self.state in self.finished_state

    def close(self) -> None:
        self.end_bar()
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)


def _no_rclpy_signal_handlers():
    """The launcher handles its signals itself (stop_signals)."""
    from rclpy.signals import SignalHandlerOptions

    return SignalHandlerOptions.NO
