"""The processes a sweep leaves behind: every graph of a sweep names its folder on its
command line (its run and scratch paths), so /proc says whether any outlived it."""

from __future__ import annotations

import time
from pathlib import Path


def processes_naming(path: Path) -> list[int]:
    """Pids of the processes whose command line contains `path`."""
    found = []
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            if str(path).encode() in cmdline.read_bytes():
                found.append(int(cmdline.parent.name))
        except OSError:
            continue
    return found


def processes_left(path: Path, timeout: float) -> list[int]:
    """Wait up to `timeout` seconds for the processes naming `path` to end; those still
    there (empty when all ended)."""
    deadline = time.monotonic() + timeout
    while processes_naming(path) and time.monotonic() < deadline:
        time.sleep(1)
    return processes_naming(path)
