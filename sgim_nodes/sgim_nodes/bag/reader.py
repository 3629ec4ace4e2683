"""Read a run's bag back in order, as plain Python records, tolerating a damaged part.

A recorder killed mid-run leaves its storage file without summary (see bag.writer): it is
read up to its last complete chunk (bag.mcap_recovery); a disk can also truncate or damage a
file. Analysis should get everything that is readable, with a warning naming each file it had
to skip, rather than nothing. Each storage file is therefore opened on its own (rosbags' own
multi-file reader fails as a whole); bags of the older layout, many small parts and staging
folders, read the same way.
Types come from the definitions embedded in the bag, so reading needs no ROS install;
load_run converts records of an older schema to today's types (bag/schema.py), as replay does.

  read_raw(path)        -> RawRecord(topic, msgtype, timestamp_ns, data) in order
  read_messages(path)   -> (topic, timestamp_ns, rosbags message) in order
  load_run(path)        -> RunRecords: every VALID sgim_msgs record as lists of dataclasses

load_run validates every record with bag/validation.py, the checks the live nodes make: a
record that fails is quarantined (listed in RunRecords.quarantined and reported with a
QuarantineWarning naming its topic, index and reason), never returned with the others; a
movement re-executed by the simulator client (a higher `attempt`) supersedes its first record.
The limits (sizes, budget, teaching set) come from the run folder's params.yaml when the bag
sits in one.
"""

from __future__ import annotations

import dataclasses
import json
import re
import warnings
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path

from sgim_nodes.bag.mcap_recovery import RecoveryError, recover
from sgim_nodes.bag.raw import Deserializer, NotABagError, RawRecord
from sgim_nodes.bag.record_checks import LIMITS_KEY, Limits, Problem, teaching_set_size
from sgim_nodes.bag.records import RECORD_TYPES, RunRecords, to_record
from sgim_nodes.bag.types import TOPICS
from sgim_nodes.bag.validation import RunValidator, summarise
from sgim_nodes.bag.writer import STAGING_PREFIX
from sgim_ros.record_key import (
    KEY_FILE,
    REEXECUTION_PATTERN,
    SIGNS_MOVEMENTS,
    TRUST_ENV,
    UNKEYED,
    MissingKey,
    read_key,
    signature_of,
    trust_unkeyed,
)

# rosbags is imported where a bag is read, not with this module: every node imports it (for
# its checks and to resume) and most never read a bag; its import costs about 0.17 s of CPU.

STORAGE_SUFFIXES = (".mcap", ".db3")
_PART_NUMBER = re.compile(r"_(\d+)\.(mcap|db3)$")

__all__ = ["BagReadWarning", "NotABagError", "QuarantineWarning", "RawRecord", "RunRecords",
           "limits_for", "load_run", "read_messages", "read_raw", "storage_files"]


class BagReadWarning(UserWarning):
    """Part of the bag could not be read; what was readable was returned."""


class QuarantineWarning(BagReadWarning):
    """Records of the bag failed validation: they were left out (the bag still holds them)."""


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
    rosbag_meta = False
    if meta.exists():
        try:
            info = _load_metadata(meta)["rosbag2_bagfile_information"]
            listed = [path / Path(p).name for p in info["relative_file_paths"]]
            rosbag_meta = True
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
    if not files and not rosbag_meta:
        raise NotABagError(_not_a_bag(path, meta))
    return files


def _not_a_bag(path: Path, meta: Path) -> str:
    """What a folder without a recording is, so the user knows where to look."""
    if (path / "bag").is_dir():
        return (f"{path} is not a bag but a run folder: its first recording is {path / 'bag'} "
                "(rebuild and analyze read run folders whole)")
    if meta.exists():
        return (f"{path} is not a bag: its metadata.yaml is not a rosbag2 one (a run's "
                "metadata.yaml? then this run folder has no bag/ recording: the run never "
                "started its recorder, or the bag was moved)")
    inside = sorted(p.name for p in path.iterdir())[:5]
    return (f"{path} is not a bag: no metadata.yaml and no .mcap or .db3 file"
            + (f" (it holds {', '.join(inside)}{', ...' if len(inside) == 5 else ''})"
               if inside else " (it is empty)"))


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


def read_raw(path: str | Path, topics: Iterable[str] | None = None,
             on_gap: Callable[[], None] | None = None,
             on_topic: Callable[[str], None] | None = None) -> Iterator[RawRecord]:
    """Every message of the bag in recording order; topics filter by name or last component.

    A file that cannot be opened or ends early is reported with a BagReadWarning and the
    reading goes on with the next one (`on_gap` is called: records may be missing there);
    NotABagError when nothing at all is readable. `on_topic` hears every topic a readable file
    declares, messages or not.
    """
    wanted = None if topics is None else set(topics)
    return _iter_raw(path, storage_files(path), wanted, on_gap or (lambda: None),
                     on_topic or (lambda _: None))


def _iter_raw(path: str | Path, files: list[Path], wanted: set[str] | None,
              on_gap: Callable[[], None], on_topic: Callable[[str], None]
              ) -> Iterator[RawRecord]:
    readable = 0
    for file in files:
        unfinished = _unfinished(file)
        count = 0
        try:
            from rosbags.rosbag2 import Reader

            reader = Reader(file)
            reader.open()
        except Exception as error:
            if file.suffix == ".mcap" and not unfinished:
                recovered = yield from _recover(file, wanted, on_gap, on_topic)
                if recovered is not None:
                    readable += 1
                    continue
            why = ("an unfinished part (the recorder was stopped while writing it)"
                   if unfinished else "unreadable")
            warnings.warn(BagReadWarning(f"skipped {file}: {why}: {error}"), stacklevel=2)
            on_gap()
            continue
        readable += 1
        try:
            for conn in reader.connections:
                on_topic(conn.topic)
            conns = [c for c in reader.connections if _wanted(c.topic, wanted)]
            if conns:
                for conn, timestamp, data in reader.messages(connections=conns):
                    count += 1
                    yield RawRecord(conn.topic, conn.msgtype, timestamp, bytes(data),
                                    conn.msgdef.data)
        except Exception as error:
            warnings.warn(BagReadWarning(
                f"{file} is damaged: read {count} messages, then: {error}"), stacklevel=2)
            if file.suffix == ".mcap":  # the chunks after the damaged one may be fine
                yield from _recover(file, wanted, on_gap, on_topic, skip=count)
            else:
                on_gap()
        finally:
            reader.close()
    if files and not readable and not all(_unfinished(f) for f in files):
        raise NotABagError(f"{path}: none of its {len(files)} storage files is readable "
                           f"({', '.join(f.name for f in files)})")


def _recover(file: Path, wanted: set[str] | None, on_gap: Callable[[], None],
             on_topic: Callable[[str], None], skip: int = 0) -> Iterator[RawRecord]:
    """The complete, undamaged chunks of an MCAP file, past the first `skip` messages already
    read; returns the number of messages read, or None when the file is no MCAP at all."""
    damage: list[str] = []
    count = 0
    try:
        for m in recover(file, on_gap=lambda why: (damage.append(why), on_gap())):
            on_topic(m.topic)
            if _wanted(m.topic, wanted):
                count += 1
                if count > skip:
                    yield RawRecord(m.topic, m.msgtype, m.timestamp_ns, m.data, m.msgdef)
    except (OSError, RecoveryError):
        return None
    skipped = f"; {len(damage)} damaged chunk(s) skipped" if damage else ""
    if skip:
        message = f"{file}: read on past the damage: {count - skip} more messages{skipped}"
    else:
        message = (f"{file} was not closed (its recorder was killed or could not write): read "
                   f"{count} messages, up to its last complete chunk{skipped}. `repair "
                   f"{file.parent}` rewrites it as a complete bag")
    warnings.warn(BagReadWarning(message), stacklevel=3)
    on_gap()  # whatever followed the last chunk is gone
    return count


def _unfinished(file: Path) -> bool:
    """A part still in its staging directory: the recorder never finished it."""
    return file.parent.name.startswith(STAGING_PREFIX)


def _wanted(topic: str, wanted: set[str] | None) -> bool:
    return wanted is None or topic in wanted or topic.rsplit("/", 1)[-1] in wanted


def read_messages(path: str | Path, topics: Iterable[str] | None = None
                  ) -> Iterator[tuple[str, int, object]]:
    """(topic, timestamp_ns, message) in recording order; messages are rosbags dataclasses."""
    deserialize = Deserializer()
    for record in read_raw(path, topics):
        yield record.topic, record.timestamp_ns, deserialize(record)


def limits_for(path: str | Path) -> Limits:
    """The validation limits of the run a bag belongs to: those its recorder validated with
    (the bag's custom_data), else its run folder's params.yaml (the launcher's), else the
    fishing world's sizes and the packaged teaching set, budget unknown; with the run's record
    key from its folder (sgim_ros/record_key.py), whichever they are."""
    path = Path(path)
    bag = path.parent if path.is_file() else path
    key = read_key(bag.parent) or read_key(bag)
    return dataclasses.replace(_limits_for(bag), record_key=key)


def _limits_for(bag: Path) -> Limits:
    try:
        info = _load_metadata(bag / "metadata.yaml")["rosbag2_bagfile_information"]
        return Limits.from_json((info.get("custom_data") or {})[LIMITS_KEY])
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        pass
    for folder in (bag, *bag.parents[:1]):
        params = folder / "params.yaml"
        if params.is_file():
            try:
                import yaml

                values = yaml.safe_load(params.read_text(encoding="utf-8"))
                return Limits.for_run(values["/**"]["ros__parameters"])
            except (OSError, ValueError, KeyError, TypeError, AttributeError) as error:
                warnings.warn(BagReadWarning(f"{params} is unreadable ({error}): validating "
                                             "with the default limits"), stacklevel=2)
            break
    # No word from the recorder: the older rule, under which only movements were signed.
    return Limits(teaching_set_size=teaching_set_size(), signing=SIGNS_MOVEMENTS)


def simulator_reexecutions(bag: Path) -> set[int] | None:
    """The movements the run's simulator says, in its logs beside the bag (the run folder's
    logs/), that it executed again; None when there are no such logs to ask."""
    bag = bag.parent if bag.is_file() else bag
    logs = sorted((bag.parent / "logs").rglob("sim_bridge*.log"))
    if not logs:
        return None
    made: set[int] = set()
    for log in logs:
        try:
            text = log.read_text(encoding="utf-8", errors="replace")
        except OSError:
            return None
        made |= {int(m.group(1)) for m in REEXECUTION_PATTERN.finditer(text)}
    return made


def load_run(path: str | Path, topics: Iterable[str] | None = None,
             limits: Limits | None = None, *, validator: RunValidator | None = None,
             into: RunRecords | None = None) -> RunRecords:
    """Every valid sgim_msgs record of the bag, one list per topic (unknown topics ignored).

    `validator` carries a run's count across its recordings (resume.load_run_folder); `into`
    appends to records already read. Quarantined records are reported once, at the end.
    """
    run = into if into is not None else RunRecords()
    validator = validator or RunValidator(limits or limits_for(path))
    already, superseded = len(validator.quarantined), len(validator.superseded)
    deserialize = Deserializer()
    wanted = set(TOPICS) if topics is None else set(topics)
    from sgim_nodes.bag.schema import SchemaError, Upgrader  # imports rosbags

    upgrader = Upgrader()

    def as_today(record: RawRecord) -> object:
        """The record as today's message (fields added since at their defaults), or as
        recorded when a field was removed or retyped since (records.to_record tolerates it)."""
        try:
            return upgrader.decode(record)
        except SchemaError:
            return deserialize(record)

    def declared(topic: str) -> None:
        run.topics.add(topic.rsplit("/", 1)[-1])

    keyless = not validator.limits.record_key
    unkeyed = False

    for record in read_raw(path, wanted, on_gap=validator.resync, on_topic=declared):
        name = record.topic.rsplit("/", 1)[-1]
        if record.msgtype != TOPICS.get(name):
            continue
        try:
            message = as_today(record)
        except NotABagError:
            raise
        except Exception as error:
            validator.quarantine(name, -1, Problem("undecodable", f"undecodable: {error}"),
                                 record.timestamp_ns)
            continue
        if keyless and not unkeyed and name == "movements" and signature_of(message):
            if not trust_unkeyed():
                raise MissingKey(
                    f"{path}: its movements are signed but the run's key ({KEY_FILE}) is not "
                    "in its folder, so a forged record cannot be told from the simulator's: "
                    f"copy {KEY_FILE} from the original folder, or set {TRUST_ENV}=1 "
                    "(analyze --trust-unkeyed) to read it unchecked")
            unkeyed = True
            warnings.warn(BagReadWarning(f"{path}: {UNKEYED} ({TRUST_ENV}): its movements' "
                                         "signatures are not checked"), stacklevel=2)
        verdict = validator.admit(name, message, record.timestamp_ns)
        if not verdict.ok:
            continue
        converted = to_record(RECORD_TYPES[name], record.timestamp_ns, message)
        records = getattr(run, name)
        if verdict.supersedes:  # the re-execution replaces the latest record of its index
            k = max(i for i, m in enumerate(records) if m.index == converted.index)
            records[k] = converted
        else:
            records.append(converted)
    run.quarantined = list(validator.quarantined)
    run.superseded = list(validator.superseded)
    replaced = validator.superseded[superseded:]
    made = simulator_reexecutions(Path(path)) if replaced else None  # the logs, when needed
    if made is not None and set(replaced) - made:
        forged = sorted(set(replaced) - made)
        warnings.warn(BagReadWarning(
            f"{path}: movement(s) {forged} replaced by a signed re-execution that the run's "
            "simulator did not make (its log shows no such re-execution): a process holding "
            f"the run's key ({KEY_FILE}) made it; the replacing record is the one the learner "
            "used"), stacklevel=2)
        replaced = sorted(set(replaced) & made)
    if replaced:
        warnings.warn(BagReadWarning(
            f"{path}: movement(s) {replaced} re-executed after the simulator gave no answer: "
            "the re-execution's record (higher attempt) is the one the learner used"),
            stacklevel=2)
    new = validator.quarantined[already:]
    if new:
        warnings.warn(QuarantineWarning(
            f"{path}: {len(new)} record(s) quarantined (kept in the bag, left out here): "
            + "; ".join(summarise(new))), stacklevel=2)
    return run


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
