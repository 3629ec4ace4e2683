"""Read a run's bag back in order, as plain Python records, tolerating a damaged part.

A recorder killed mid-run leaves its bag as finished parts plus, possibly, an unfinished one
(see bag.writer); a disk can also truncate a file. Analysis should get everything that is
readable, with a warning naming each file it had to skip, rather than nothing. Each storage
file is therefore opened on its own (rosbags' own multi-file reader fails as a whole).
Types come from the definitions embedded in the bag, so reading needs no ROS install.

  read_raw(path)        -> RawRecord(topic, msgtype, timestamp_ns, data) in order
  read_messages(path)   -> (topic, timestamp_ns, rosbags message) in order
  load_run(path)        -> RunRecords: every sgim_msgs topic as lists of dataclasses
"""

from __future__ import annotations

import json
import re
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from sgim_nodes.bag.records import RECORD_TYPES, RunRecords, to_record
from sgim_nodes.bag.types import TOPICS
from sgim_nodes.bag.writer import STAGING_PREFIX

STORAGE_SUFFIXES = (".mcap", ".db3")
_PART_NUMBER = re.compile(r"_(\d+)\.(mcap|db3)$")

__all__ = ["BagReadWarning", "NotABagError", "RawRecord", "RunRecords", "load_run",
           "read_messages", "read_raw", "storage_files"]


class NotABagError(ValueError):
    """The path is not a rosbag2 bag, or none of its files can be read."""


class BagReadWarning(UserWarning):
    """Part of the bag could not be read; what was readable was returned."""


@dataclass(frozen=True)
class RawRecord:
    topic: str
    msgtype: str
    timestamp_ns: int  # when the recorder received it
    data: bytes  # CDR, as it crossed the wire
    msgdef: str = field(default="", repr=False)


def _part_key(path: Path) -> tuple[int, str]:
    match = _PART_NUMBER.search(path.name)
    return (int(match.group(1)) if match else 2**31, path.name)


def storage_files(path: str | Path) -> list[Path]:
    """The bag's storage files in recording order: those listed in metadata.yaml, then complete
    files it does not list yet, then unfinished parts left by a killed recorder."""
    path = Path(path)
    if not path.exists():
        raise NotABagError(f"{path} does not exist")
    if path.is_file():
        if path.suffix not in STORAGE_SUFFIXES:
            raise NotABagError(
                f"{path} is not a bag: expected a bag directory or a .mcap / .db3 file")
        return [path]
    listed: list[Path] = []
    meta = path / "metadata.yaml"
    if meta.exists():
        try:
            info = _load_metadata(meta)["rosbag2_bagfile_information"]
            listed = [path / Path(p).name for p in info["relative_file_paths"]]
        except (ValueError, KeyError, TypeError) as error:
            warnings.warn(BagReadWarning(
                f"{meta} is unreadable ({error}): reading the storage files found instead"),
                stacklevel=2)
    present = sorted((p for p in path.iterdir() if p.suffix in STORAGE_SUFFIXES), key=_part_key)
    for missing in (p for p in listed if not p.exists()):
        warnings.warn(BagReadWarning(f"{missing} is listed in {meta} but missing: skipped"),
                      stacklevel=2)
    files = [p for p in listed if p.exists()] + [p for p in present if p not in listed]
    staging = sorted(path.glob(f"{STAGING_PREFIX}*/*"), key=lambda p: int(p.parent.name[6:])
                     if p.parent.name[6:].isdigit() else 2**31)
    files += [p for p in staging if p.suffix in STORAGE_SUFFIXES]
    if not files and not meta.exists():
        raise NotABagError(f"{path} is not a bag: no metadata.yaml and no .mcap or .db3 file")
    return files


def _load_metadata(meta: Path) -> dict:
    text = meta.read_text(encoding="utf-8")
    try:
        return json.loads(text)  # what bag.writer writes: fast to parse
    except json.JSONDecodeError:
        from ruamel.yaml import YAML, YAMLError

        try:
            return YAML(typ="safe").load(text)
        except YAMLError as error:
            raise ValueError(str(error).splitlines()[0]) from None


def read_raw(path: str | Path, topics: Iterable[str] | None = None) -> Iterator[RawRecord]:
    """Every message of the bag in recording order; topics filter by name or last component.

    A file that cannot be opened or ends early is reported with a BagReadWarning and the
    reading goes on with the next one; NotABagError when nothing at all is readable.
    """
    wanted = None if topics is None else set(topics)
    return _iter_raw(path, storage_files(path), wanted)


def _iter_raw(path: str | Path, files: list[Path], wanted: set[str] | None
              ) -> Iterator[RawRecord]:
    readable = 0
    for file in files:
        unfinished = _unfinished(file)
        count = 0
        try:
            reader = Reader(file)
            reader.open()
        except Exception as error:
            why = ("an unfinished part (the recorder was stopped while writing it)"
                   if unfinished else "unreadable")
            warnings.warn(BagReadWarning(f"skipped {file}: {why}: {error}"), stacklevel=2)
            continue
        readable += 1
        try:
            conns = [c for c in reader.connections if _wanted(c.topic, wanted)]
            if conns:
                for conn, timestamp, data in reader.messages(connections=conns):
                    count += 1
                    yield RawRecord(conn.topic, conn.msgtype, timestamp, bytes(data),
                                    conn.msgdef.data)
        except Exception as error:
            warnings.warn(BagReadWarning(
                f"{file} is damaged: read {count} messages, then: {error}"), stacklevel=2)
        finally:
            reader.close()
    if files and not readable and not all(_unfinished(f) for f in files):
        raise NotABagError(f"{path}: none of its {len(files)} storage files is readable "
                           f"({', '.join(f.name for f in files)})")


def _unfinished(file: Path) -> bool:
    """A part still in its staging directory: the recorder never finished it."""
    return file.parent.name.startswith(STAGING_PREFIX)


def _wanted(topic: str, wanted: set[str] | None) -> bool:
    return wanted is None or topic in wanted or topic.rsplit("/", 1)[-1] in wanted


class _Deserializer:
    """Deserialises with the definitions embedded in the bag (no ROS install needed)."""

    def __init__(self) -> None:
        self.store: Typestore = get_typestore(Stores.ROS2_JAZZY)

    def __call__(self, record: RawRecord) -> object:
        if record.msgtype not in self.store.types:
            self._register(record)
        return self.store.deserialize_cdr(record.data, record.msgtype)

    def _register(self, record: RawRecord) -> None:
        types: dict = {}
        if record.msgdef:
            types = get_types_from_msg(record.msgdef, record.msgtype)
        else:  # a bag written without definitions: use our own .msg files
            from sgim_nodes.bag.types import sgim_types

            types = sgim_types()
        self.store.register({k: v for k, v in types.items() if k not in self.store.types})
        if record.msgtype not in self.store.types:
            raise NotABagError(f"no definition of {record.msgtype} in the bag")


def read_messages(path: str | Path, topics: Iterable[str] | None = None
                  ) -> Iterator[tuple[str, int, object]]:
    """(topic, timestamp_ns, message) in recording order; messages are rosbags dataclasses."""
    deserialize = _Deserializer()
    for record in read_raw(path, topics):
        yield record.topic, record.timestamp_ns, deserialize(record)


def load_run(path: str | Path, topics: Iterable[str] | None = None) -> RunRecords:
    """Every sgim_msgs record of the bag, one list per topic (unknown topics are ignored)."""
    run = RunRecords()
    deserialize = _Deserializer()
    wanted = set(TOPICS) if topics is None else set(topics)
    for record in read_raw(path, wanted):
        name = record.topic.rsplit("/", 1)[-1]
        if record.msgtype != TOPICS.get(name):
            continue
        getattr(run, name).append(to_record(RECORD_TYPES[name], record.timestamp_ns,
                                            deserialize(record)))
    run.movements = superseded_removed(run.movements, str(path))
    return run


def superseded_removed(movements: list, where: str) -> list:
    """One record per movement index: the last one.

    An index is recorded twice when the simulator died after publishing a movement but before
    its answer reached the learner: the learner executed that movement again with the same
    index (sim_client.py), and only the later record is the one it learned from.
    """
    last = {m.index: k for k, m in enumerate(movements)}
    if len(last) == len(movements):
        return movements
    doubled = sorted({m.index for k, m in enumerate(movements) if last[m.index] != k})
    warnings.warn(f"{where}: movement(s) {doubled} recorded more than once (re-executed after "
                  "a simulator restart); keeping the last record of each", BagReadWarning,
                  stacklevel=3)
    return [m for k, m in enumerate(movements) if last[m.index] == k]


def load_movements(path: str | Path) -> list:
    return load_run(path, ["movements"]).movements


def load_goals(path: str | Path) -> list:
    return load_run(path, ["goals"]).goals


def load_competences(path: str | Path) -> list:
    return load_run(path, ["competences"]).competences


def load_region_maps(path: str | Path) -> list:
    return load_run(path, ["region_map"]).region_map


def load_demonstrations(path: str | Path) -> list:
    return load_run(path, ["demonstrations"]).demonstrations


def load_evaluations(path: str | Path) -> list:
    return load_run(path, ["evaluations"]).evaluations


def load_run_statuses(path: str | Path) -> list:
    return load_run(path, ["run_status"]).run_status
