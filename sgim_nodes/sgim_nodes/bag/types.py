"""A rosbags typestore that knows every sgim_msgs message, and the topics a run records
(declared with the graph's other interfaces in sgim_ros/interfaces.py).

Bags must carry their message definitions so that analysis needs no ROS install: rosbags
embeds what its typestore knows, so every sgim_msgs type is registered here from the .msg
files themselves (the installed share dir, or the source tree next to this repository when the
workspace is not built). Nothing here imports rclpy.
"""

from __future__ import annotations

import contextlib
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

from sgim_ros.interfaces import (  # noqa: F401 - the run's topics, for the bag's readers
    PACKAGE,
    RECORDED_TOPICS,
    STATE_TOPICS,
    TOPICS,
    VIEW_TOPICS,
)

if TYPE_CHECKING:  # rosbags is imported when a typestore is made (bag/reader.py says why)
    from rosbags.typesys.store import Typestore

SOURCE_MSG_DIR = Path(__file__).resolve().parents[3] / PACKAGE / "msg"


class MessageDefinitionsNotFound(FileNotFoundError):
    """Neither the installed sgim_msgs nor the source tree holds the .msg files."""


def msg_dir() -> Path:
    """The directory of sgim_msgs' .msg files: installed share dir first, else the sources."""
    candidates: list[Path] = []
    try:
        from ament_index_python.packages import (
            PackageNotFoundError,
            get_package_share_directory,
        )

        with contextlib.suppress(PackageNotFoundError):
            candidates.append(Path(get_package_share_directory(PACKAGE)) / "msg")
    except ImportError:  # no ROS at all: the source tree is enough
        pass
    candidates.append(SOURCE_MSG_DIR)
    for directory in candidates:
        if any(directory.glob("*.msg")):
            return directory
    raise MessageDefinitionsNotFound(
        f"no {PACKAGE} .msg files in {', '.join(str(c) for c in candidates)}: build the "
        "workspace (./bootstrap.sh) or run from a checkout of the repository"
    )


def sgim_types(directory: Path | None = None) -> dict:
    """Parsed definitions of every sgim_msgs message, keyed by full type name."""
    from rosbags.typesys import get_types_from_msg

    directory = directory or msg_dir()
    types: dict = {}
    for path in sorted(directory.glob("*.msg")):
        name = f"{PACKAGE}/msg/{path.stem}"
        types.update(get_types_from_msg(path.read_text(encoding="utf-8"), name))
    return types


@cache
def typestore() -> Typestore:
    """The Jazzy typestore plus every sgim_msgs type (registered at once, so nested types
    such as RegionMap's Region resolve whatever the file order). Shared: do not register
    conflicting definitions into it."""
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(sgim_types())
    return store
