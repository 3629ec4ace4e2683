"""A rosbag2 bag written as ONE storage file, in small durable chunks, so a kill loses little.

A run's recording is one bag directory holding `metadata.yaml` and one storage file
(`<bag>/<bag>.mcap`, or `.db3`), written by rosbags' Writer, so that Foxglove, `rosbags` and
`ros2 bag` open it as any other bag. What makes it durable is the checkpoint: every
`chunk_seconds` or `chunk_messages`, the open MCAP chunk is closed and the file flushed to the
operating system (SQLite: the transaction is committed). A SIGKILL then loses only what came
after the last checkpoint; the file it leaves has no summary and no metadata.yaml, and the
readers (bag.reader, bag.mcap_recovery) read it up to its last complete chunk, or
`python -m sgim_nodes.bag.repair BAG` rewrites it as a complete file.

rosbags has no public call for "close the chunk now": the checkpoint uses its MCAP storage's
close_chunk() and file object, checked at open so that another rosbags version fails at once
with a clear message rather than silently losing the durability. Nothing here imports rclpy.
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from sgim_nodes.bag.types import typestore as sgim_typestore

if TYPE_CHECKING:  # rosbags is imported when a bag is opened (bag/reader.py says why)
    from rosbags.typesys.store import Typestore

STORAGES = ("mcap", "sqlite3")  # rosbags' StoragePlugin.MCAP and .SQLITE3
STAGING_PREFIX = ".part_"  # the staging folders of bags written before one file per segment


class BagWriteError(RuntimeError):
    """The bag cannot be written (the output exists, a bad storage name, a closed bag)."""


@dataclass
class BagWriter:
    """Write CDR messages into `path`, checkpointing every chunk_seconds / chunk_messages.

    Call `add_topic()` for every topic first (each is declared in the file at once, with its
    message definition), `write()` for each message, `maybe_checkpoint()` now and then (a timer)
    so that a quiet graph still makes its last messages durable, and `close()` in a finally.
    Any OSError (a full disk, ...) propagates: the caller decides to stop.
    """

    path: Path
    storage: str = "mcap"
    chunk_seconds: float = 0.5
    chunk_messages: int = 250
    store: Typestore | None = None
    custom_data: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        if self.storage not in STORAGES:
            raise BagWriteError(f"storage must be one of {sorted(STORAGES)}, not {self.storage!r}")
        if self.chunk_seconds <= 0 or self.chunk_messages < 1:
            raise BagWriteError("chunk_seconds must be > 0 and chunk_messages >= 1")
        if self.path.exists():
            raise BagWriteError(f"{self.path} exists already: choose a new bag directory")
        self.store = self.store or sgim_typestore()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        from rosbags.rosbag2 import StoragePlugin, Writer

        plugin = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}[self.storage]
        self._writer = Writer(self.path, version=9, storage_plugin=plugin)
        self._writer.open()
        self._check_storage()
        self._connections: dict[str, object] = {}
        self._last_checkpoint = time.monotonic()
        self._closed = False
        self.messages_written = 0
        self.messages_durable = 0  # up to the last checkpoint: what survives a kill
        self.checkpoints = 0

    def _check_storage(self) -> None:
        storage = self._writer.storage
        needed = ("close_chunk", "chunk", "bio") if self.storage == "mcap" else ("conn",)
        if not all(hasattr(storage, name) for name in needed):
            self._writer.abort()
            raise BagWriteError(f"this rosbags version's {self.storage} writer cannot be "
                                "checkpointed (bag/writer.py needs its chunk control): pin "
                                "rosbags as requirements.txt does")

    @property
    def file(self) -> Path:
        """The storage file (rosbags names it after the bag directory)."""
        return self.path / f"{self.path.name}{'.mcap' if self.storage == 'mcap' else '.db3'}"

    def add_topic(self, topic: str, msgtype: str) -> None:
        """Declare a topic before writing to it."""
        if topic in self._connections:
            if self._connections[topic].msgtype != msgtype:
                raise BagWriteError(f"topic {topic} already has type "
                                    f"{self._connections[topic].msgtype}")
            return
        self._connections[topic] = self._writer.add_connection(topic, msgtype,
                                                               typestore=self.store)

    def write(self, topic: str, timestamp_ns: int, data: bytes | memoryview) -> None:
        """Append one CDR-serialised message; may checkpoint."""
        if self._closed:
            raise BagWriteError("the bag is closed")
        if topic not in self._connections:
            raise BagWriteError(f"unknown topic {topic!r}: call add_topic first")
        self._writer.write(self._connections[topic], timestamp_ns, data)
        self.messages_written += 1
        if self.messages_written - self.messages_durable >= self.chunk_messages:
            self.checkpoint()

    def maybe_checkpoint(self) -> None:
        """Checkpoint if the last one is older than chunk_seconds (call from a timer)."""
        if time.monotonic() - self._last_checkpoint >= self.chunk_seconds:
            self.checkpoint()

    def checkpoint(self) -> None:
        """Make everything written so far survive a kill of this process."""
        self._last_checkpoint = time.monotonic()
        if self._closed or self.messages_written == self.messages_durable:
            return
        storage = self._writer.storage
        if self.storage == "mcap":
            if storage.chunk.bio.tell():
                storage.close_chunk()
            storage.bio.flush()
        else:
            storage.conn.commit()
        self.messages_durable = self.messages_written
        self.checkpoints += 1

    def close(self) -> None:
        """Write the file's summary and the bag's metadata.yaml; idempotent, safe in a
        finally. After a write error the file is left as it is (readable up to its last
        checkpoint) and the error propagates."""
        if self._closed:
            return
        self._closed = True
        for key, value in self.custom_data.items():
            self._writer.set_custom_data(key, str(value))
        self._writer.close()
        self.messages_durable = self.messages_written

    def abort(self) -> None:
        """Stop without writing more (after a write error): the file keeps its checkpoints."""
        if not self._closed:
            self._closed = True
            with contextlib.suppress(OSError):
                self._writer.abort()
