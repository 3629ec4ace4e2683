"""The terminal side of `human_input`: the line-reading loop, the thread that spins the node
beside it, readline's history, and stdin read through a queue when it is not a terminal.

Why apart from the node: this is plumbing between a person's keyboard and any node that
offers `lock`, `prompt_text`, `handle_line`, `end_of_input`, `busy`, `poll`, `finished`,
`at_prompt` and `out` (see human_input_node.py, whose docstring says why two threads).
"""

from __future__ import annotations

import contextlib
import os
import queue
import signal
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TextIO

from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor

HISTORY = Path(os.environ.get("SGIM_TEACHER_HISTORY", "~/.sgim_teacher_history")).expanduser()


class Spinner(threading.Thread):
    """Spins the node until stopped; wakes the reading thread when the node is finished."""

    def __init__(self, node: Any) -> None:
        super().__init__(name="human-input-ros", daemon=False)
        self.node = node
        self.stopping = threading.Event()
        self.executor = SingleThreadedExecutor(context=node.context)
        self.executor.add_node(node)

    def run(self) -> None:
        try:
            while not self.stopping.is_set() and self.node.context.ok():
                self.executor.spin_once(timeout_sec=0.05)
                self.node.poll()
                if self.node.finished and not self.stopping.is_set():
                    self.stopping.set()
                    if self.node.at_prompt:  # leave input() in the main thread
                        os.kill(os.getpid(), signal.SIGINT)
        except ExternalShutdownException:
            pass
        finally:
            with contextlib.suppress(Exception):
                self.executor.remove_node(self.node)
            self.executor.shutdown()

    def stop(self) -> None:
        self.stopping.set()
        self.join(timeout=5)


def setup_readline() -> None:
    """Line editing and a history kept across sessions, for a person at a terminal."""
    import atexit
    import readline

    with contextlib.suppress(OSError):
        readline.read_history_file(HISTORY)
    readline.set_history_length(1000)
    atexit.register(lambda: _save_history(readline))


def _save_history(readline) -> None:
    with contextlib.suppress(OSError):
        readline.write_history_file(HISTORY)


class PipeLines:
    """The lines of a stdin that is not a terminal, read by a daemon thread.

    A SIGINT that lands after `input()` wrote its prompt but before its read() blocks is
    handled (Python's flag is set) without interrupting that read, which then waits for the
    next line for ever: Ctrl-C, and the spinner's wake-up at the run's end, were lost (seen
    under load). Here the main thread waits on a queue in short steps, between which Python
    raises a pending KeyboardInterrupt. A terminal keeps input() and readline's editing."""

    def __init__(self, stream: TextIO, out: TextIO) -> None:
        self.out = out
        self.lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._pump, args=(stream,), name="human-input-stdin",
                         daemon=True).start()

    def _pump(self, stream: TextIO) -> None:
        for line in stream:
            self.lines.put(line.rstrip("\n"))
        self.lines.put(None)  # end of input

    def input(self, text: str) -> str:
        self.out.write(text)
        self.out.flush()
        while True:
            try:
                line = self.lines.get(timeout=0.1)
            except queue.Empty:
                continue
            if line is None:
                self.lines.put(None)  # every later read sees the end too
                raise EOFError
            return line


def run(node: Any, read_line: Callable[[str], str] = input) -> str:
    """Read and obey lines until quit, end of input or the run's end; returns why it ended."""
    spinner = Spinner(node)
    spinner.start()
    try:
        while not node.finished:
            with node.lock:
                text = node.prompt_text()
                node.at_prompt = True
            try:
                line = read_line(text)
            except EOFError:
                node.at_prompt = False
                node.end_of_input()
                return "end of input"
            node.at_prompt = False
            with node.lock:
                node.handle_line(line)
            while node.busy and not node.finished:
                time.sleep(0.02)
        return "finished"
    except KeyboardInterrupt:
        node.at_prompt = False
        if node.finished:  # woken by the spinner: the run is over, already said
            print(file=node.out)
            return "run over"
        raise
    finally:
        spinner.stop()
