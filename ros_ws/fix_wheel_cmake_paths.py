"""Point the ROS 2 wheels' CMake exports at this machine's Python.

The ros-jazzy-* wheels are built in a manylinux container and their exported CMake files name
that container's Python include and numpy include directories. CMake then refuses to generate
("Imported target ... includes non-existent path"). Rewriting the two paths to this
interpreter's is enough; running it again changes nothing.

Usage: python fix_wheel_cmake_paths.py VENV
"""

from __future__ import annotations

import sys
import sysconfig
from pathlib import Path

import numpy

BUILDER_PYTHON_INCLUDE = "/opt/python/cp311-cp311/include/python3.11"
BUILDER_NUMPY_INCLUDE = "/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include"


def fix(venv: Path) -> int:
    """Rewrite the builder's paths in every CMake file of the venv; return how many changed."""
    replacements = {
        BUILDER_NUMPY_INCLUDE: numpy.get_include(),
        BUILDER_PYTHON_INCLUDE: sysconfig.get_paths()["include"],
    }
    changed = 0
    for path in (venv / "share").rglob("*.cmake"):
        text = path.read_text(encoding="utf-8", errors="surrogateescape")
        new = text
        for old, here in replacements.items():  # numpy first: it contains the Python prefix
            new = new.replace(old, here)
        if new != text:
            path.write_text(new, encoding="utf-8", errors="surrogateescape")
            changed += 1
    return changed


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1 or args[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if args and args[0] in ("-h", "--help") else 2
    venv = Path(args[0])
    if not (venv / "share").is_dir():
        print(
            f"fix_wheel_cmake_paths: {venv}/share does not exist: is this the venv?",
            file=sys.stderr,
        )
        return 1
    print(f"fix_wheel_cmake_paths: {fix(venv)} CMake files updated", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
