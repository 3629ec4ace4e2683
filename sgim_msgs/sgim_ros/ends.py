"""The ends channel of a process that hosts several nodes: one ``NAME CODE`` line per node as
it ends, written by the process (sgim_ros/host.py) into a pipe the launcher made, and read by
the launcher (graph/processes.py), which thus sees a node end while its process goes on.

A pipe, not a file: a run's disk may be full exactly when its nodes end (the recorder's exit
code 3 says so), and a pipe needs no room."""

from __future__ import annotations

import contextlib
import os
import sys


class Ends:
    """The writing side: the inherited pipe's descriptor, or None when started by hand."""

    def __init__(self, fd: int | None) -> None:
        self.fd = fd
        self.written: set[str] = set()

    def write(self, name: str, code: int) -> None:
        if self.fd is None or name in self.written:
            return
        self.written.add(name)
        try:
            os.write(self.fd, f"{name} {code}\n".encode())  # one write: whole, under PIPE_BUF
        except OSError as error:  # the launcher is gone: nobody to tell
            print(f"[{name}] its end not told to the launcher: {error}", file=sys.stderr,
                  flush=True)


class EndsReader:
    """The launcher's side of one process's pipe: the ends told so far, read without
    blocking."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        os.set_blocking(fd, False)
        self.ends: dict[str, int] = {}
        self._partial = b""
        self.closed = False

    def read(self) -> dict[str, int]:
        while not self.closed:
            try:
                chunk = os.read(self.fd, 4096)
            except BlockingIOError:
                break
            except OSError:
                chunk = b""
            if not chunk:  # every write end is closed: the process has ended
                self.close()
                break
            lines = (self._partial + chunk).split(b"\n")
            self._partial = lines.pop()
            for line in lines:
                name, _, code = line.decode(errors="replace").rpartition(" ")
                if name and code.lstrip("-").isdigit():
                    self.ends.setdefault(name, int(code))
        return self.ends

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            with contextlib.suppress(OSError):
                os.close(self.fd)
