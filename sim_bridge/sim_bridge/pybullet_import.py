"""pybullet, imported without the line its C module prints when it loads.

pybullet's module initialisation writes "pybullet build time: ..." to the process's stderr,
so every command that imports the world showed it before its own output, and a refusal's one
line came second. The package's __init__ loads it here, first: that line is dropped, anything
else written to stderr meanwhile is passed on, and the modules that `import pybullet` then
take it from sys.modules (the world's own modules stay as they are: they count in the learner
fingerprint).
"""

from __future__ import annotations

import contextlib
import ctypes
import importlib.util
import os
import sys
import tempfile
from types import ModuleType

BUILD_TIME_LINE = b"pybullet build time:"
STDERR = 2


def _flush_c_streams() -> None:
    """Write out what C code has buffered (stderr is not, a piped stdout is)."""
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).fflush(None)


def import_pybullet() -> ModuleType | None:
    """The pybullet module, its build-time line left out of the process's stderr; None when
    it is not installed (what needs it says so when it imports it)."""
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    if importlib.util.find_spec("pybullet") is None:
        return None
    with contextlib.suppress(AttributeError, OSError, ValueError):
        sys.stderr.flush()  # what was written before the import goes out first, as it was
    _flush_c_streams()
    try:
        saved = os.dup(STDERR)
    except OSError:  # no stderr at all: nothing to keep clean
        import pybullet

        return pybullet
    try:
        with tempfile.TemporaryFile() as caught:
            os.dup2(caught.fileno(), STDERR)
            try:
                import pybullet
            finally:
                _flush_c_streams()
                os.dup2(saved, STDERR)
            caught.seek(0)
            kept = b"".join(line for line in caught.read().splitlines(keepends=True)
                            if not line.startswith(BUILD_TIME_LINE))
        if kept:
            os.write(STDERR, kept)
    finally:
        os.close(saved)
    return pybullet

