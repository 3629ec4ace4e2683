"""A rosbag2 bag written as a sequence of small, finished storage files, so a kill loses little.

rosbags' Writer only produces a readable file when it is closed (a killed or aborted writer
leaves an unreadable file and no metadata). So one run's bag directory is written as rosbag2
"split" files, as `ros2 bag record --max-bag-duration` does: each part is written by its own
Writer into a hidden staging directory, closed after `split_seconds` or `split_messages`,
moved next to the others as `<bag>_<k>.mcap` (or .db3), and the bag's metadata.yaml is
rewritten atomically to list it. A SIGKILL therefore loses only the open part: at most
`split_messages` messages, or what arrived in the last `split_seconds`.

metadata.yaml is written as JSON (valid YAML): rewriting it at every split must stay cheap
even with hundreds of parts, and ruamel's dumper is not. Nothing here imports rclpy.
"""

from __future__ import annotations

import json
import os
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path

from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys.store import Typestore

from sgim_nodes.bag.types import typestore as sgim_typestore

STORAGES = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}
STAGING_PREFIX = ".part_"


class BagWriteError(RuntimeError):
    """The bag cannot be written (the output exists, a bad storage name, a closed bag)."""


@dataclass
class _Topic:
    msgtype: str
    count: int = 0  # messages in the finished parts


@dataclass
class SplitBagWriter:
    """Write CDR messages into `path`, finishing a part every split_seconds / split_messages.

    Call `write()` for each message, `maybe_split()` now and then (a timer) so that a quiet
    graph still finishes its last messages, and `close()` in a finally.
    """

    path: Path
    storage: str = "mcap"
    split_seconds: float = 1.0
    split_messages: int = 500
    store: Typestore | None = None
    custom_data: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        if self.storage not in STORAGES:
            raise BagWriteError(f"storage must be one of {sorted(STORAGES)}, not {self.storage!r}")
        if self.split_seconds <= 0 or self.split_messages < 1:
            raise BagWriteError("split_seconds must be > 0 and split_messages >= 1")
        if self.path.exists():
            raise BagWriteError(f"{self.path} exists already: choose a new bag directory")
        self.path.mkdir(parents=True)
        self.store = self.store or sgim_typestore()
        self._topics: dict[str, _Topic] = {}
        self._files: list[dict] = []
        self._part: Writer | None = None
        self._part_connections: dict[str, object] = {}
        self._part_count = 0
        self._part_opened = 0.0
        self._part_start = 2**63 - 1
        self._part_end = 0
        self._closed = False
        self.messages_written = 0  # finished and still open parts
        self.messages_finished = 0  # in finished parts only: what survives a kill

    @property
    def suffix(self) -> str:
        return ".mcap" if self.storage == "mcap" else ".db3"

    def add_topic(self, topic: str, msgtype: str) -> None:
        """Declare a topic before writing to it (its type is needed for every part)."""
        if topic in self._topics and self._topics[topic].msgtype != msgtype:
            raise BagWriteError(f"topic {topic} already has type {self._topics[topic].msgtype}")
        self._topics.setdefault(topic, _Topic(msgtype))

    def write(self, topic: str, timestamp_ns: int, data: bytes | memoryview) -> None:
        """Append one CDR-serialised message; may finish the current part."""
        if self._closed:
            raise BagWriteError("the bag is closed")
        if topic not in self._topics:
            raise BagWriteError(f"unknown topic {topic!r}: call add_topic first")
        if self._part is None:
            self._open_part()
        if topic not in self._part_connections:
            self._part_connections[topic] = self._part.add_connection(
                topic, self._topics[topic].msgtype, typestore=self.store
            )
        self._part.write(self._part_connections[topic], timestamp_ns, data)
        self._part_start = min(self._part_start, timestamp_ns)
        self._part_end = max(self._part_end, timestamp_ns)
        self.messages_written += 1
        if self._part_messages() >= self.split_messages:
            self.finish_part()

    def maybe_split(self) -> None:
        """Finish the open part if it is older than split_seconds (call from a timer)."""
        if self._part is not None and time.monotonic() - self._part_opened >= self.split_seconds:
            self.finish_part()

    def _part_messages(self) -> int:
        return self.messages_written - self.messages_finished

    def _staging(self, k: int) -> Path:
        return self.path / f"{STAGING_PREFIX}{k}"

    def _open_part(self) -> None:
        self._part = Writer(
            self._staging(self._part_count), version=9, storage_plugin=STORAGES[self.storage]
        )
        self._part.open()
        self._part_connections = {}
        self._part_opened = time.monotonic()
        self._part_start, self._part_end = 2**63 - 1, 0

    def finish_part(self) -> None:
        """Close the open part, move it into the bag and list it in metadata.yaml."""
        part, self._part = self._part, None
        if part is None:
            return
        staging = self._staging(self._part_count)
        part.close()  # a failure here leaves the staging dir: that part is lost, not the bag
        name = f"{self.path.name}_{self._part_count}{self.suffix}"
        (staging / f"{staging.name}{self.suffix}").replace(self.path / name)
        shutil.rmtree(staging, ignore_errors=True)
        count = self._part_messages()
        for conn in part.connections:
            self._topics[conn.topic].count += part.counts[conn.id]
        self._files.append(
            {
                "path": name,
                "starting_time": {"nanoseconds_since_epoch": self._part_start},
                "duration": {"nanoseconds": max(0, self._part_end - self._part_start)},
                "message_count": count,
            }
        )
        self._part_count += 1
        self.messages_finished = self.messages_written
        self._write_metadata()

    def _write_metadata(self) -> None:
        start = min((f["starting_time"]["nanoseconds_since_epoch"] for f in self._files),
                    default=0)
        end = max((f["starting_time"]["nanoseconds_since_epoch"] + f["duration"]["nanoseconds"]
                   for f in self._files), default=0)
        info = {
            "version": 9,
            "storage_identifier": self.storage,
            "relative_file_paths": [f["path"] for f in self._files],
            "duration": {"nanoseconds": max(0, end - start)},
            "starting_time": {"nanoseconds_since_epoch": start},
            "message_count": self.messages_finished,
            "topics_with_message_count": [
                {
                    "topic_metadata": {
                        "name": topic,
                        "type": t.msgtype,
                        "serialization_format": "cdr",
                        "offered_qos_profiles": [],
                        "type_description_hash": self.store.hash_rihs01(t.msgtype),
                    },
                    "message_count": t.count,
                }
                for topic, t in self._topics.items()
                if t.count
            ],
            "compression_format": "",
            "compression_mode": "",
            "files": self._files,
            "custom_data": self.custom_data or None,
            "ros_distro": "rosbags",
        }
        tmp = self.path / "metadata.yaml.tmp"
        tmp.write_text(json.dumps({"rosbag2_bagfile_information": info}, indent=1), "utf8")
        os.replace(tmp, self.path / "metadata.yaml")

    def close(self) -> None:
        """Finish the open part; idempotent, safe in a finally. An empty bag gets an empty
        metadata.yaml so that it still reads as a (empty) bag."""
        if self._closed:
            return
        self._closed = True
        try:
            self.finish_part()
        finally:
            if not (self.path / "metadata.yaml").exists():
                self._write_metadata()
