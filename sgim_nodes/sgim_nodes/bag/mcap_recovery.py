"""Read an MCAP file that was never closed, up to its last complete chunk.

A recorder killed mid-run leaves its MCAP file without summary and footer (bag.writer flushes
each chunk as it closes it): rosbags' reader refuses such a file, and a run's history must not
be lost for it. This scans the data section record by record (MCAP spec: opcode, uint64
length, body) and yields the messages of every complete record, skipping a chunk whose body
is damaged (`on_gap` is called: messages may be missing there) and stopping where the file
ends mid-record. Only the record framing of the MCAP spec is used; no ROS install needed.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

MAGIC = b"\x89MCAP0\r\n"
OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK, OP_DATA_END = (
    0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x0F)


class RecoveryError(ValueError):
    """Not an MCAP file, or nothing in it can be read."""


@dataclass(frozen=True)
class RecoveredMessage:
    topic: str
    msgtype: str
    msgdef: str
    timestamp_ns: int
    data: bytes


@dataclass
class _Schema:
    name: str
    data: str


def _string(body: memoryview, at: int) -> tuple[str, int]:
    (size,) = struct.unpack_from("<I", body, at)
    return bytes(body[at + 4: at + 4 + size]).decode("utf-8"), at + 4 + size


def _decompress(compression: str, data: bytes, size: int) -> bytes:
    if compression == "":
        return data
    if compression == "zstd":
        import zstandard

        return zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    if compression == "lz4":
        import lz4.frame

        return lz4.frame.decompress(data)
    raise RecoveryError(f"unknown chunk compression {compression!r}")


class _Scanner:
    def __init__(self) -> None:
        self.schemas: dict[int, _Schema] = {}
        self.channels: dict[int, tuple[str, int]] = {}  # id -> (topic, schema id)
        self.complete_chunks = 0

    def records(self, data: memoryview, start: int) -> Iterator[tuple[int, memoryview, int]]:
        """(opcode, body, end offset) of every complete record from `start`."""
        at = start
        while at + 9 <= len(data):
            op = data[at]
            (length,) = struct.unpack_from("<Q", data, at + 1)
            end = at + 9 + length
            if end > len(data):
                return  # the file ends inside this record: written up to here
            yield op, data[at + 9: end], end
            at = end

    def messages(self, body: memoryview, op: int) -> Iterator[RecoveredMessage]:
        if op == OP_SCHEMA:
            (sid,) = struct.unpack_from("<H", body, 0)
            name, at = _string(body, 2)
            _, at = _string(body, at)  # encoding
            (size,) = struct.unpack_from("<I", body, at)
            self.schemas[sid] = _Schema(name, bytes(body[at + 4: at + 4 + size]).decode())
        elif op == OP_CHANNEL:
            cid, sid = struct.unpack_from("<HH", body, 0)
            topic, _ = _string(body, 4)
            self.channels[cid] = (topic, sid)
        elif op == OP_MESSAGE:
            cid, _, log_time, _ = struct.unpack_from("<HIQQ", body, 0)
            topic, sid = self.channels[cid]
            schema = self.schemas.get(sid, _Schema("", ""))
            yield RecoveredMessage(topic, schema.name, schema.data, log_time, bytes(body[22:]))

    def chunk(self, body: memoryview) -> list[RecoveredMessage]:
        """The messages of one chunk, all or none (a damaged chunk raises)."""
        _, _, size, crc = struct.unpack_from("<QQQI", body, 0)
        compression, at = _string(body, 28)
        (length,) = struct.unpack_from("<Q", body, at)
        raw = _decompress(compression, bytes(body[at + 8: at + 8 + length]), size)
        if len(raw) != size or (crc and zlib.crc32(raw) != crc):
            raise RecoveryError("chunk size or checksum mismatch")
        inner = memoryview(raw)
        out: list[RecoveredMessage] = []
        filled = 0
        for op, record, filled in self.records(inner, 0):  # noqa: B007 - read after the loop
            out.extend(self.messages(record, op))
        if filled != size:
            raise RecoveryError("chunk records do not fill the chunk")
        return out


def recover(path: str | Path, on_gap: Callable[[str], None] | None = None
            ) -> Iterator[RecoveredMessage]:
    """Every message of the complete records of an MCAP file, in file order."""
    data = memoryview(Path(path).read_bytes())
    if bytes(data[:8]) != MAGIC:
        raise RecoveryError(f"{path} is not an MCAP file (bad magic)")
    scanner = _Scanner()
    for op, body, _ in scanner.records(data, 8):
        if op in (OP_DATA_END, OP_FOOTER):
            return
        try:
            if op == OP_CHUNK:
                yield from scanner.chunk(body)
                scanner.complete_chunks += 1
            else:
                yield from scanner.messages(body, op)
        except (struct.error, KeyError, UnicodeDecodeError, RecoveryError) as error:
            if on_gap is not None:
                on_gap(f"a damaged record was skipped ({type(error).__name__}: {error})")
