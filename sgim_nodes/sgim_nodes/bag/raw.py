"""A bag's raw records and their decoding with the definitions the bag itself holds.

The reader (bag/reader.py) and the schema upgrader (bag/schema.py) both build on these, so
they live below both: neither imports the other's module for them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

# rosbags is imported where a bag is decoded, not with this module (bag/reader.py says why).


class NotABagError(ValueError):
    """The path is not a rosbag2 bag, or none of its files can be read."""


@dataclass(frozen=True)
class RawRecord:
    topic: str
    msgtype: str
    timestamp_ns: int  # when the recorder received it
    data: bytes  # CDR, as it crossed the wire
    msgdef: str = field(default="", repr=False)



class Deserializer:
    """Deserialises with the definitions embedded in the bag (no ROS install needed)."""

    def __init__(self) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.store: Typestore = get_typestore(Stores.ROS2_JAZZY)

    def __call__(self, record: RawRecord) -> object:
        return self.store_for(record).deserialize_cdr(record.data, record.msgtype)

    def store_for(self, record: RawRecord) -> Typestore:
        """The typestore that holds the record's type as the bag defines it."""
        if record.msgtype not in self.store.types:
            self._register(record)
        return self.store

    def _register(self, record: RawRecord) -> None:
        types: dict = {}
        if record.msgdef:
            from rosbags.typesys import get_types_from_msg

            types = get_types_from_msg(record.msgdef, record.msgtype)
        else:  # a bag written without definitions: use our own .msg files
            from sgim_nodes.bag.types import sgim_types

            types = sgim_types()
        self.store.register({k: v for k, v in types.items() if k not in self.store.types})
        if record.msgtype not in self.store.types:
            raise NotABagError(f"no definition of {record.msgtype} in the bag")
