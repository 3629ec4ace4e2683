"""Records of older bags as today's messages: the one place that decides whether a record's
recorded schema is today's type, and converts it when it is not.

Messages gain fields over the versions (Movement.attempt, Demonstration.content and
help_request: `git log -p sgim_msgs/msg`). A bag keeps the definitions it was recorded with,
and the readers decode every record with them (bag.reader); but the CDR bytes of an older
layout, published with today's type, are garbage to today's subscribers. `Upgrader` compares
each recorded type with today's, field by field and through nested types, once per recorded
definition: an unchanged schema keeps its bytes (the fast path); an older one is decoded with
the bag's definition (the readers' decoder) and re-encoded as today's type, the fields it
lacks at the defaults the readers' records give them (bag/records.py), else the type's zero.
A field removed, renamed or retyped since, or a type that no longer exists, cannot be
converted without guessing: SchemaError names the topic and the field. Nothing here imports
rclpy.
"""

from __future__ import annotations

import dataclasses
from functools import cache

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.typesys.base import normalize_fieldname
from rosbags.typesys.store import Typestore

from sgim_nodes.bag.raw import Deserializer, NotABagError, RawRecord
from sgim_nodes.bag.records import RECORD_TYPES
from sgim_nodes.bag.types import TOPICS, typestore

# Numpy element types of rosbags' numeric arrays and sequences (strings and messages: lists).
_DTYPES = {"bool": np.bool_, "byte": np.int8, "char": np.uint8, "int8": np.int8,
           "uint8": np.uint8, "int16": np.int16, "uint16": np.uint16, "int32": np.int32,
           "uint32": np.uint32, "int64": np.int64, "uint64": np.uint64,
           "float32": np.float32, "float64": np.float64}


class SchemaError(ValueError):
    """A recorded type cannot become today's without guessing: a field was removed, renamed
    or retyped since, or the type no longer exists."""


class _Incompatible(Exception):
    def __init__(self, field: str, why: str) -> None:
        super().__init__(f"field '{field}' {why}")


@cache
def record_defaults(msgtype: str) -> dict[str, object]:
    """What the readers' records give the fields a bag may lack (the record dataclasses'
    defaults, bag/records.py), by field name, for the message type `msgtype`."""
    kinds = {RECORD_TYPES[topic] for topic, name in TOPICS.items() if name == msgtype}
    return {f.name: f.default for kind in kinds for f in dataclasses.fields(kind)
            if f.default is not dataclasses.MISSING}


class Upgrader:
    """Turns the raw records of a bag into records of today's types (see the module doc)."""

    def __init__(self, current: Typestore | None = None) -> None:
        self.current = current or typestore()
        self._verdicts: dict[tuple[str, str], bool] = {}  # (type, recorded definition): same?
        self._recorded: dict[str, Deserializer] = {}  # per recorded definition text

    def is_current(self, record: RawRecord) -> bool:
        """Whether the record's bytes are already today's layout; SchemaError when they can
        never be converted to it."""
        key = (record.msgtype, record.msgdef)
        if key not in self._verdicts:
            self._verdicts[key] = self._check(record)
        return self._verdicts[key]

    def upgrade(self, record: RawRecord) -> RawRecord:
        """The record itself when its schema is today's, else the same record re-encoded as
        today's type (its definition then empty: today's, as in a bag written without)."""
        if self.is_current(record):
            return record
        message = self.decode(record)
        data = bytes(self.current.serialize_cdr(message, record.msgtype))
        return dataclasses.replace(record, data=data, msgdef="")

    def decode(self, record: RawRecord) -> object:
        """The record as a rosbags message of today's type, whatever schema it was recorded
        with (decoded with the bag's own definition, then converted)."""
        if self.is_current(record):
            return self.current.deserialize_cdr(record.data, record.msgtype)
        old = self._recorded[record.msgdef]
        return self._convert(old(record), record.msgtype)

    def default_message(self, msgtype: str) -> object:
        """Today's `msgtype` with every field at the value an older record lacking it gets."""
        return self._convert(None, msgtype)

    def _check(self, record: RawRecord) -> bool:
        if record.msgtype not in self.current.fielddefs:
            raise SchemaError(f"{record.topic}: the recorded type {record.msgtype} no longer "
                              "exists: this bag cannot be replayed as today's messages")
        if not record.msgdef:  # a bag written without definitions is read with today's
            return True
        try:
            recorded = self._recorded.setdefault(record.msgdef, Deserializer()
                                                 ).store_for(record)
        except NotABagError:
            raise
        except Exception as error:  # a damaged definition: nothing to convert with
            raise SchemaError(f"{record.topic}: the recorded definition of {record.msgtype} "
                              f"is unreadable: {error}") from None
        try:
            return _same_type(recorded, self.current, record.msgtype, "")
        except _Incompatible as error:
            raise SchemaError(
                f"{record.topic}: the recorded {record.msgtype}'s {error}: this bag cannot "
                "be replayed as today's messages (an older version of the toolkit can)"
            ) from None

    def _convert(self, old: object | None, msgtype: str) -> object:
        """Today's `msgtype` from `old` (a message of the same fields or fewer, or None)."""
        defaults = record_defaults(msgtype)
        values = {}
        for name, desc in self.current.fielddefs[msgtype][1]:
            attribute = normalize_fieldname(name)
            if old is not None and hasattr(old, attribute):
                values[attribute] = self._value(getattr(old, attribute), desc)
            elif name in defaults:
                values[attribute] = defaults[name]
            else:
                values[attribute] = self._zero(desc)
        return self.current.types[msgtype](**values)

    def _value(self, value: object, desc: tuple) -> object:
        kind, detail = desc
        if kind == Nodetype.NAME:
            return self._convert(value, detail)
        if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE) and detail[0][0] == Nodetype.NAME:
            return [self._convert(item, detail[0][1]) for item in value]
        return value

    def _zero(self, desc: tuple) -> object:
        kind, detail = desc
        if kind == Nodetype.BASE:
            return {"string": "", "wstring": "", "bool": False, "float32": 0.0,
                    "float64": 0.0}.get(detail[0], 0)
        if kind == Nodetype.NAME:
            return self._convert(None, detail)
        inner, size = detail
        count = size if kind == Nodetype.ARRAY else 0
        if inner[0] == Nodetype.BASE and inner[1][0] in _DTYPES:
            return np.zeros(count, dtype=_DTYPES[inner[1][0]])
        return [self._zero(inner) for _ in range(count)]


def _same_type(old: Typestore, new: Typestore, msgtype: str, where: str) -> bool:
    """True when `msgtype` has the same fields, in the same order, in both stores (nested
    types too); False when `new` only adds or reorders fields; _Incompatible otherwise."""
    old_fields, new_fields = dict(old.fielddefs[msgtype][1]), dict(new.fielddefs[msgtype][1])
    same = list(old_fields) == list(new_fields)
    for name, desc in old_fields.items():
        path = f"{where}.{name}" if where else name
        if name not in new_fields:
            raise _Incompatible(path, f"({_spell(desc)}) no longer exists (removed or renamed)")
        same &= _same_field(old, new, desc, new_fields[name], path)
    return same


def _same_field(old: Typestore, new: Typestore, a: tuple, b: tuple, path: str) -> bool:
    if a[0] != b[0] or (a[0] == Nodetype.BASE and a[1] != b[1]) or (
            a[0] == Nodetype.NAME and a[1] != b[1]) or (
            a[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE) and a[1][1] != b[1][1]):
        raise _Incompatible(path, f"was {_spell(a)}, is now {_spell(b)}")
    if a[0] == Nodetype.NAME:
        return _same_type(old, new, a[1], path)
    if a[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        return _same_field(old, new, a[1][0], b[1][0], f"{path}[]")
    return True


def _spell(desc: tuple) -> str:
    """A field type as a .msg file writes it."""
    kind, detail = desc
    if kind == Nodetype.BASE:
        return detail[0] + (f"<={detail[1]}" if detail[1] else "")
    if kind == Nodetype.NAME:
        return detail
    size = detail[1] if kind == Nodetype.ARRAY else (f"<={detail[1]}" if detail[1] else "")
    return f"{_spell(detail[0])}[{size}]"
