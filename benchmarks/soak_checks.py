"""The chaos soak's checks of a finished run (benchmarks/chaos_soak.py), written apart from the
project's readers where they can be: what a run must hold whatever was done to it.

- every segment's MCAP file read by the mcap library and rosbags alone, the signatures checked
  with the stdlib's hmac: the movements the run's key signed count 1..N once each (a
  re-execution replacing its index), and every demonstration the learner took is one the
  run's teacher signed and gave;
- the project's rebuild against an uninterrupted run of the same seed made by the
  single-process runner: the movements before the first interruption are the reference's, bit
  for bit; every teacher turn has its word and, when something was shown, the learner took
  it and imitated it as many times as it owed, with its competence recorded; every
  evaluation point is there; the tree holds every competence; no forged pair is in memory.
"""

from __future__ import annotations

import hashlib
import hmac
import struct
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import yaml

SIGNATURE_BYTES = 16
IMITATIONS = 5  # the learner's imitation_count (LearnerConfig's default)
FORGED_OUTCOME = (0.9, 0.9)  # where every forged record of the soak says its action lands


def recorded(run_dir: Path, topics: set[str]) -> Iterator[tuple[str, Any]]:
    """(topic, message) of every segment, in order, as far as each file is whole (a recorder
    that met a full disk leaves its file truncated): the mcap library reads, rosbags decodes
    with the definitions the file embeds."""
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader
    from rosbags.typesys import Stores, get_typestore

    files = sorted(run_dir.glob("bag*/*.mcap"), key=lambda f: (len(f.parent.name), f.parent.name))
    for file in files:
        store = get_typestore(Stores.ROS2_JAZZY)
        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        try:
            with file.open("rb") as stream:
                for record in StreamReader(stream, emit_chunks=False).records:
                    if isinstance(record, Schema):
                        schemas[record.id] = record
                    elif isinstance(record, Channel):
                        channels[record.id] = record
                    elif isinstance(record, Message):
                        channel = channels[record.channel_id]
                        topic = channel.topic.rsplit("/", 1)[-1]
                        if topic not in topics:
                            continue
                        schema = schemas[channel.schema_id]
                        if schema.name not in store.types:
                            store.register(_definitions(schema.name, schema.data.decode()))
                        yield topic, store.deserialize_cdr(record.data, schema.name)
        except Exception:  # the file ends where its recorder stopped: what came before counts
            pass


def _definitions(name: str, text: str) -> dict:
    """The types of a ros2msg schema as an MCAP file embeds them (the type, then its
    dependencies after '=' lines)."""
    from rosbags.typesys import get_types_from_msg

    parts = text.split("=" * 80 + "\n")
    types = dict(get_types_from_msg(parts[0], name))
    for part in parts[1:]:
        header, _, body = part.partition("\n")
        types.update(get_types_from_msg(body, header.removeprefix("MSG: ").strip()))
    return types


def _floats(values: Any) -> bytes:
    data = np.asarray(values, dtype="<f8").ravel()
    return struct.pack("<I", data.size) + data.tobytes()


def _text(value: str) -> bytes:
    data = str(value).encode()
    return struct.pack("<I", len(data)) + data


def _mac(key: bytes, body: bytes) -> bytes:
    return hmac.new(key, body, hashlib.sha256).digest()[:SIGNATURE_BYTES]


def movement_signed(key: bytes, m: Any) -> bool:
    body = struct.pack("<QBBBQ", int(m.index), int(m.attempt), int(m.process), int(m.status),
                       int(m.goal_index))
    body += _floats(m.action) + _floats(m.outcome) + _floats(m.goal)
    return hmac.compare_digest(_mac(key, body), bytes(bytearray(m.signature)))


def teaching_signed(key: bytes, topic: str, d: Any) -> bool:
    body = (struct.pack("<IQiI", int(d.index), int(d.movement_index), int(d.teaching_set_index),
                        int(d.help_request))
            + _floats(d.action) + _floats(d.outcome) + _text(d.source) + _text(d.content))
    return hmac.compare_digest(_mac(key, _text(topic) + body), bytes(bytearray(d.signature)))


def _pair(d: Any) -> tuple[bytes, bytes]:
    return bytes(np.asarray(d.action, "<f8")), bytes(np.asarray(d.outcome, "<f8"))


def independent_problems(run_dir: Path, movements: int) -> tuple[list[str], set[tuple]]:
    """The checks that use no project code (the module's doc, first part), and the
    (action, outcome) pairs of the demonstrations the run's arbiter signed as taken (the bag
    also holds whatever forgeries were published: the readers must leave them out)."""
    key = bytes.fromhex((run_dir / "record.key").read_text().strip())
    seen: set[int] = set()
    order: list[int] = []
    given: set[tuple] = set()
    taken: list[Any] = []  # signed by the run's arbiter
    for topic, m in recorded(run_dir, {"movements", "demonstrations", "demonstrations_taken"}):
        if topic == "movements":
            if movement_signed(key, m) and int(m.index) not in seen:
                seen.add(int(m.index))
                order.append(int(m.index))
        elif topic == "demonstrations":
            if teaching_signed(key, topic, m):
                given.add(_pair(m))
        elif teaching_signed(key, topic, m):
            taken.append(m)
    problems = []
    if order != list(range(1, movements + 1)):
        problems.append(f"signed movements are not 1..{movements} once each ({len(order)} found)")
    for d in taken:
        if _pair(d) not in given:
            problems.append(f"demonstration {d.index} taken at {d.movement_index} was never "
                            "given by the run's teacher")
    return problems, {_pair(d) for d in taken}


def reference_movements(seed: int, movements: int, eval_every: int, period: int) -> list[dict]:
    """The movements of an uninterrupted run of the same seed and settings, made by the
    single-process runner (the graph makes its very movements)."""
    from sgim_nodes.core.learner_registry import SGIM_D, make_learner
    from sgim_nodes.core.runner import build_world, run
    from sgim_nodes.core.social_config import SocialConfig

    world = build_world("fishing", seed)
    learner = make_learner(SGIM_D, world.env.action_dim, world.env.outcome_dim, seed,
                           scale=world.scale)
    records: list[dict] = []
    run(learner, world, movements, eval_every, seed, records.append,
        SocialConfig(demonstration_period=period))
    return [r for r in records if r["type"] == "movement"]


def run_problems(run_dir: Path, seed: int, movements: int, eval_every: int,
                 period: int) -> list[str]:
    """Every check of the module's doc; [] when the run holds what it must."""
    from sgim_nodes.bag.rebuild import rebuild_from_records
    from sgim_nodes.bag.resume import load_run_folder

    problems, taken = independent_problems(run_dir, movements)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        records = load_run_folder(run_dir)
    forged = [d for d in records.demonstrations_taken if _pair(d) not in taken]
    if forged:
        problems.append(f"the readers take {len(forged)} demonstration(s) the arbiter never "
                        f"signed (the first at movement {forged[0].movement_index})")
    state = rebuild_from_records(records)
    if state.n_movements != movements:
        problems.append(f"rebuild holds {state.n_movements} movements")
    if np.any(np.all(np.isclose(state.memory.outcomes, FORGED_OUTCOME), axis=1)):
        problems.append("memory holds a forged pair")
    meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())
    resumed = meta.get("resumed") or []
    cut = resumed[0]["from_movement"] if resumed else movements
    reference = reference_movements(seed, movements, eval_every, period)
    for m, r in zip(records.movements[:cut], reference[:cut], strict=False):
        if not np.array_equal(m.action, np.asarray(r["action"])):
            problems.append(f"movement {m.index} (before the first interruption at {cut}) "
                            "differs from the uninterrupted run")
            break
    words = {d.movement_index for d in records.demonstrations if not d.help_request}
    shown = {d.movement_index for d in records.demonstrations if d.shown}
    taken = {d.movement_index: d for d in records.demonstrations_taken}
    imitations = {m.index for m in records.movements if m.process == 2}
    measured = {c.movement_index for c in records.competences if c.from_demonstration}
    for k in range(0, movements, period):
        if k not in words:
            problems.append(f"no teacher's word at turn {k}")
        elif k in shown and k not in taken:
            problems.append(f"turn {k}: a demonstration shown, none taken")
        elif k in taken:
            owed = min(IMITATIONS, movements - k)
            made = [i for i in range(k + 1, k + owed + 1) if i in imitations]
            if len(made) != owed:
                problems.append(f"turn {k}: {len(made)} of its {owed} imitations")
            elif k + owed not in measured:
                problems.append(f"turn {k}: its imitation's competence is missing")
    points = {e.movement_index for e in records.evaluations}
    missing = [p for p in range(0, movements + 1, eval_every) if p not in points]
    if missing:
        problems.append(f"no evaluation at {missing}")
    if state.n_competences != len(records.competences):
        problems.append(f"the tree holds {state.n_competences} competences, the bag "
                        f"{len(records.competences)}")
    if state.region_map_matches() is False:
        problems.append("the rebuilt tree's leaves are not the last recorded map's")
    return problems
