"""Records signed by the run's nodes, so that no other publisher can pass for them.

Why: the graph's records travel on a DDS domain any process may publish on, and a well-formed
forged Movement (a "re-execution" of the latest index with attempt 1, or a record that comes
before the real one) looked to every node and reader exactly like the simulator's. The
launcher now makes a secret for each run (`record.key` in its folder, mode 0600), hands it to
its nodes in the environment (never as a ROS parameter: any process on the domain can read
those), and the simulator signs every Movement with it: HMAC-SHA256 over the fields that make
the movement, the first 16 bytes in `Movement.signature`. Every consumer checks the signature
(bag/record_checks.py) and quarantines a record that lacks it or whose signature is wrong; the
bag readers take the key from the run's folder. What teaches the learner is signed the same
way by the node that makes it: a teacher's demonstration (`demonstrations`, signed by the
teacher, expert, human or web node), the arbiter's `demonstrations_taken` and its help
requests; each under its topic's name, so that one cannot be replayed as another. A teacher
node started by hand for a run (teacher "external") signs with the key of the run's folder,
given in SGIM_RECORD_KEY.

A run made without a key (an older bag, a node started alone) is read as before; a folder
whose movements are signed but whose key is gone (copied without it) is refused, since
without the key a forgery reads like the simulator's record, unless SGIM_TRUST_UNKEYED=1
(`analyze --trust-unkeyed`) says to read it unchecked.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import re
import secrets
import struct
from pathlib import Path
from typing import Any

import numpy as np

ENV = "SGIM_RECORD_KEY"
KEY_FILE = "record.key"
SIGNATURE_BYTES = 16
# What a run's records carry (Limits.signing, kept in each bag): a bag recorded before the
# teaching records were signed has their signatures empty, and is read as it was made.
SIGNS_MOVEMENTS = 1
SIGNS_TEACHING = 2
SIGNS_COMPETENCES = 3
SIGNED_SINCE = {"demonstrations": SIGNS_TEACHING, "demonstrations_taken": SIGNS_TEACHING,
                "help_requests": SIGNS_TEACHING, "competences": SIGNS_COMPETENCES}
"""The records, besides movements, that the node publishing them signs: those that teach the
learner and the competences its interest is made of, with the signing level that added each."""
TEACHING_TOPICS = tuple(SIGNED_SINCE)
# What the simulator logs when it executes a movement again for a client that got no answer:
# a signed re-execution its log does not show was made by another holder of the key.
REEXECUTION_LOG = "re-executed movement {index} (attempt {attempt})"
REEXECUTION_PATTERN = re.compile(r"re-executed movement (\d+) \(attempt (\d+)\)")
TRUST_ENV = "SGIM_TRUST_UNKEYED"
UNKEYED = "read without its record key"  # how a trusted keyless run is named in reports


class MissingKey(ValueError):
    """A run's movements are signed, but its folder has no key to check them with."""


def trust_unkeyed() -> bool:
    """Whether the user said to read signed runs whose key is missing, unchecked."""
    return os.environ.get(TRUST_ENV, "").strip() not in ("", "0")


def new_key() -> str:
    return secrets.token_hex(32)


def from_environment() -> str:
    """The run's key as the launcher hands it to its nodes ("" when started alone)."""
    return os.environ.get(ENV, "").strip()


def write_key(run_dir: Path, key: str) -> None:
    """Keep the key in the run folder, readable by its owner only (resume and the readers need
    it)."""
    path = Path(run_dir) / KEY_FILE
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(key + "\n")


def read_key(run_dir: Path) -> str:
    """The key of the run in ``run_dir`` ("" when it has none: made before keys existed)."""
    try:
        return (Path(run_dir) / KEY_FILE).read_text().strip()
    except OSError:
        return ""


def _floats(values: Any) -> bytes:
    data = np.asarray(values if values is not None else (), dtype="<f8").ravel()
    return struct.pack("<I", data.size) + data.tobytes()


def movement_signature(key: str, movement: Any) -> bytes:
    """The signature of a Movement-like record (fields read by name)."""
    head = struct.pack("<QBBBQ", int(movement.index), int(getattr(movement, "attempt", 0)),
                       int(movement.process), int(movement.status),
                       int(getattr(movement, "goal_index", 0)))
    body = (head + _floats(movement.action) + _floats(movement.outcome)
            + _floats(getattr(movement, "goal", ())))
    return hmac.new(bytes.fromhex(key), body, hashlib.sha256).digest()[:SIGNATURE_BYTES]


def _text(value: Any) -> bytes:
    data = str(value).encode("utf-8")
    return struct.pack("<I", len(data)) + data


def teaching_signature(key: str, topic: str, record: Any) -> bytes:
    """The signature of a Demonstration-like (``demonstrations``, ``demonstrations_taken``),
    HelpRequest-like (``help_requests``) or Competence-like (``competences``) record, fields
    read by name."""
    if topic == "competences":
        body = (struct.pack("<QQdI?", int(record.goal_index), int(record.movement_index),
                            float(record.competence), int(record.movements_used),
                            bool(record.from_demonstration))
                + _floats(record.goal) + _floats(record.reached) + _text(record.strategy))
    elif topic == "help_requests":
        body = (struct.pack("<IQ", int(record.index), int(record.movement_index))
                + _floats(record.goal) + _text(record.teacher) + _text(record.content))
    elif topic in ("demonstrations", "demonstrations_taken"):
        body = (struct.pack("<IQiI", int(record.index), int(record.movement_index),
                            int(record.teaching_set_index), int(record.help_request))
                + _floats(record.action) + _floats(record.outcome) + _text(record.source)
                + _text(record.content))
    else:
        raise ValueError(f"no signature is defined for {topic!r} records")
    return hmac.new(bytes.fromhex(key), _text(topic) + body,
                    hashlib.sha256).digest()[:SIGNATURE_BYTES]


def sign_teaching(topic: str, record: Any, key: str | None = None) -> Any:
    """Sign ``record`` of ``topic`` in place with ``key`` (the run's, from the environment,
    by default) and return it; left unsigned when there is no key (a node started alone)."""
    key = from_environment() if key is None else key
    if key:
        record.signature = list(teaching_signature(key, topic, record))
    return record


def teaching_signed_by(key: str, topic: str, record: Any) -> bool:
    """Whether the record carries the signature the run's node gives it."""
    return hmac.compare_digest(signature_of(record), teaching_signature(key, topic, record))


def signature_of(movement: Any) -> bytes:
    """The record's signature as bytes, whatever carries it (rclpy's array, rosbags' numpy
    array, bytes; none in a record of an older bag)."""
    found = getattr(movement, "signature", None)
    return b"" if found is None else bytes(bytearray(found))


def signed_by(key: str, movement: Any) -> bool:
    """Whether the record carries the signature the run's simulator gives it."""
    return hmac.compare_digest(signature_of(movement), movement_signature(key, movement))
