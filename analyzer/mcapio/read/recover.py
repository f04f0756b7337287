"""Reading an MCAP file record by record without its summary: unfinished or damaged files."""

from __future__ import annotations

import io
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import IO, Any

from analyzer.mcapio.read.records import (
    MAX_RECORD,
    MESSAGE_FIXED,
    OPCODE_CHANNEL,
    OPCODE_CHUNK,
    OPCODE_DATA_END,
    OPCODE_MESSAGE,
    OPCODE_METADATA,
    OPCODE_SCHEMA,
    RECORD_HEAD,
    ChunkDamage,
    chunk_payload,
    find_chunk,
    parse_chunk,
    plausible_record,
    walk,
)

_MESSAGE_HEAD = struct.Struct("<HIQ")  # channel id, sequence, log time


@dataclass(frozen=True, slots=True)
class Damage:
    """A part of a recording that could not be read: where on the timeline, and why."""

    log_time: int  # ns; 0 when the damaged part does not say
    detail: str


@dataclass(frozen=True, slots=True)
class Found:
    """One message met by the scan: channel id, log time and its bytes."""

    channel_id: int
    log_time: int
    data: bytes


@dataclass
class Recovery:
    """What the sequential read of an unfinished or damaged file could read."""

    messages: int = 0
    good_bytes: int = 0  # bytes up to the end of the last complete record
    total_bytes: int = 0
    damaged_chunks: int = 0
    skipped_bytes: int = 0  # garbage jumped over to resynchronise
    unknown_channel: int = 0  # messages whose channel record was lost
    data_complete: bool = False  # the data section ended properly; only the summary is bad
    reason: str = ""
    summary_problem: str = ""  # set when a finished file's summary was not believed

    def describe(self) -> str:
        lost = self.total_bytes - self.good_bytes
        if self.summary_problem:
            text = (
                f"{self.summary_problem}; read sequentially instead: {self.messages} messages "
                f"({self.good_bytes} of {self.total_bytes} bytes readable"
            )
        else:
            text = (
                f"recovered {self.messages} messages from an unfinished recording "
                f"({self.good_bytes} of {self.total_bytes} bytes readable"
            )
        if lost > 0 and not self.data_complete:
            text += f", {lost} bytes of unfinished data at the end"
        text += ")"
        if self.damaged_chunks:
            text += f"; {self.damaged_chunks} damaged chunk(s) skipped"
        if self.skipped_bytes:
            text += f"; {self.skipped_bytes} bytes of damaged records skipped"
        if self.unknown_channel:
            text += f"; {self.unknown_channel} messages of channels whose definition was lost"
        if self.reason and not self.summary_problem:
            text += f"; {self.reason}"
        return text


@dataclass
class Scan:
    """State of one sequential read: channels and schemas met so far, and what went wrong."""

    size: int
    report: Recovery
    schemas: dict[int, Any] = field(default_factory=dict)
    channels: dict[int, Any] = field(default_factory=dict)
    damage: list[Damage] = field(default_factory=list)


def _read_record(opcode: int, body: bytes) -> Any:
    from mcap.data_stream import ReadDataStream
    from mcap.records import Channel, Metadata, Schema

    kind = {OPCODE_SCHEMA: Schema, OPCODE_CHANNEL: Channel, OPCODE_METADATA: Metadata}[opcode]
    return kind.read(ReadDataStream(io.BytesIO(body)))  # type: ignore[attr-defined]


def scan_records(f: IO[bytes], scan: Scan) -> Iterator[Found | Damage]:
    """Every message of the data section, in file order, plus a Damage for each part lost.

    A chunk is used only when its lengths agree and it passes decompression and its CRC.
    After a record with a bad opcode or length, the read resynchronises on the next intact
    chunk; if there is none, the rest is the unfinished tail of a killed recorder.
    """
    report = scan.report
    size = scan.size
    pos = 8
    report.good_bytes = min(size, 8)
    while pos + 9 <= size:
        f.seek(pos)
        opcode, length = RECORD_HEAD.unpack(f.read(9))
        end = pos + 9 + length
        body = b""
        sane = length <= MAX_RECORD and end <= size
        if sane:
            body = f.read(length)
            sane = plausible_record(opcode, body)
        if not sane:
            found = find_chunk(f, pos + 1, size)
            if found is None:
                if end > size or length > MAX_RECORD:
                    report.reason = f"stopped at byte {pos}: the last record is cut short"
                else:
                    report.reason = f"stopped at byte {pos}: the rest does not parse"
                return
            report.skipped_bytes += found - pos
            damage = Damage(0, f"bytes {pos}-{found} do not parse; read on from the chunk there")
            scan.damage.append(damage)
            yield damage
            pos = found
            continue
        if opcode == OPCODE_CHUNK:
            head = parse_chunk(body)
            try:
                records = chunk_payload(body, head)
                found_records = list(_chunk_messages(records, scan))
            except ChunkDamage as exc:
                report.damaged_chunks += 1
                damage = Damage(head.start_time, f"damaged chunk at byte {pos} skipped: {exc}")
                scan.damage.append(damage)
                yield damage
            else:
                yield from found_records
        elif opcode == OPCODE_DATA_END:
            report.good_bytes = end
            report.data_complete = True
            report.reason = "data section complete, summary missing or damaged"
            return
        elif opcode == OPCODE_MESSAGE:
            yield from _chunk_messages(RECORD_HEAD.pack(opcode, length) + body, scan)
        elif opcode in (OPCODE_SCHEMA, OPCODE_CHANNEL):
            _remember(opcode, body, scan)
        report.good_bytes = end
        pos = end


def _remember(opcode: int, body: bytes, scan: Scan) -> None:
    record = _read_record(opcode, body)
    if opcode == OPCODE_SCHEMA:
        scan.schemas[record.id] = record
    else:
        scan.channels[record.id] = record


def _chunk_messages(data: bytes, scan: Scan) -> Iterator[Found]:
    """Messages of a chunk's records (schemas and channels are remembered on the way)."""
    out: list[Found] = []
    for opcode, body, end in walk(data):
        if opcode == OPCODE_MESSAGE:
            if end - body < MESSAGE_FIXED:
                raise ChunkDamage("a message record is too short")
            channel_id, _, log_time = _MESSAGE_HEAD.unpack_from(data, body)
            out.append(Found(channel_id, log_time, data[body + MESSAGE_FIXED : end]))
        elif opcode in (OPCODE_SCHEMA, OPCODE_CHANNEL):
            try:
                _remember(opcode, data[body:end], scan)
            except Exception as exc:  # a record that does not parse
                raise ChunkDamage(f"a schema or channel record does not parse ({exc})") from None
    return iter(out)


def metadata_before_data(f: IO[bytes], size: int) -> dict[str, dict[str, str]]:
    """Metadata records read sequentially from the start, up to the first chunk or damage."""
    out: dict[str, dict[str, str]] = {}
    pos = 8
    while pos + 9 <= size:
        f.seek(pos)
        opcode, length = RECORD_HEAD.unpack(f.read(9))
        if opcode == OPCODE_CHUNK or length > MAX_RECORD or pos + 9 + length > size:
            break
        body = f.read(length)
        if not plausible_record(opcode, body):
            break
        if opcode == OPCODE_METADATA:
            record = _read_record(opcode, body)
            out[record.name] = dict(record.metadata)
        pos += 9 + length
    return out
