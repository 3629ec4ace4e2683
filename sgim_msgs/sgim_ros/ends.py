"""The ends file of a process that hosts several nodes: one ``NAME CODE`` line per node as it
ends, written by the process (sgim_ros/host.py) and read by the run launcher
(graph/processes.py), which thus sees a node end while its process goes on."""

from __future__ import annotations

import sys
from pathlib import Path


class Ends:
    """The process's ends file: one ``NAME CODE`` line per member that has ended, written at
    once, so that the launcher sees an end while the process goes on."""

    def __init__(self, path: Path | None) -> None:
        self.path = path
        self.written: set[str] = set()

    def write(self, name: str, code: int) -> None:
        if self.path is None or name in self.written:
            return
        self.written.add(name)
        try:
            with open(self.path, "a", encoding="utf-8") as out:
                out.write(f"{name} {code}\n")
        except OSError as error:  # the launcher then sees the process's own end
            print(f"[{name}] end not written to {self.path}: {error}", file=sys.stderr,
                  flush=True)


def read_ends(path: Path) -> dict[str, int]:
    """Member name -> exit code, for those whose end the file holds."""
    ends: dict[str, int] = {}
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        return ends
    for line in text.splitlines():
        name, _, code = line.rpartition(" ")
        if name and code.lstrip("-").isdigit():
            ends.setdefault(name, int(code))
    return ends
