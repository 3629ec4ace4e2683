"""The web teacher page's two pictures: the lake behind its plot, and the latest
demonstration's cast as a GIF.

The cast is drawn by `sim_bridge.tools.render_cast` in a low-priority child process, so a
run is not slowed by it; only the latest demonstration waits to be drawn (a newer one replaces
it), and the page shows the last finished picture meanwhile.
"""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from sim_bridge import scaling
from sim_bridge.lake import is_water
from teacher.web.app import LAND_RGB, WATER_RGB


def lake_png(size: int = 240) -> bytes:
    """The water (blue) and land (sand) of the outcome space [-1, 1]^2, y up, as a PNG."""
    from PIL import Image

    u = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    ux, uy = np.meshgrid(u, -u)  # row 0 is y = +1
    water = is_water(scaling.outcome_to_world(np.column_stack([ux.ravel(), uy.ravel()])))
    rgb = np.where(water.reshape(size, size, 1), np.array(WATER_RGB, np.uint8),
                   np.array(LAND_RGB, np.uint8)).astype(np.uint8)
    buffer = io.BytesIO()
    Image.fromarray(rgb, "RGB").save(buffer, format="PNG", optimize=True)
    return buffer.getvalue()


class CastRenderer:
    """The latest demonstration's cast, drawn in a child process, polled by the node."""

    def __init__(self, enabled: bool, warn) -> None:
        self.enabled, self._warn = enabled, warn
        self.picture: bytes | None = None  # the last GIF drawn
        self._dir = Path(tempfile.mkdtemp(prefix="web_teacher_cast_"))
        self._child: tuple[subprocess.Popen, Path, str] | None = None
        self._next: tuple[np.ndarray, str] | None = None

    def queue(self, action, caption: str) -> None:
        """Draw this action's cast next (a newer one replaces one not started yet)."""
        if self.enabled:
            self._next = (np.asarray(action, dtype=float), caption)

    def poll(self) -> tuple[str | None, bool]:
        """(the caption of a picture just finished, or None; whether one is being drawn)."""
        finished = None
        if self._child is not None:
            child, gif, caption = self._child
            if child.poll() is None:
                return None, True
            self._child = None
            if child.returncode == 0 and gif.is_file():
                self.picture, finished = gif.read_bytes(), caption
            else:
                self._warn(f"render_cast failed (exit {child.returncode})")
        if self._next is not None:
            action, caption = self._next
            self._next = None
            action_file = self._dir / "action.yaml"
            action_file.write_text(str([float(v) for v in action]))
            gif = self._dir / "cast.gif"
            gif.unlink(missing_ok=True)
            command = [sys.executable, "-m", "sim_bridge.tools.render_cast", "--action",
                       str(action_file), "--out", str(gif), "--size", "240x180", "--fps", "20",
                       "--quiet"]
            self._child = (subprocess.Popen(command, stdout=subprocess.DEVNULL,
                                            stderr=subprocess.DEVNULL,
                                            preexec_fn=lambda: os.nice(10)), gif, caption)
        return finished, self._child is not None

    def stop(self) -> None:
        """End a drawing under way and remove the scratch folder."""
        if self._child is not None and self._child[0].poll() is None:
            self._child[0].kill()
            self._child[0].wait(timeout=5)
        for file in self._dir.glob("*"):
            file.unlink(missing_ok=True)
        with contextlib.suppress(OSError):
            self._dir.rmdir()
