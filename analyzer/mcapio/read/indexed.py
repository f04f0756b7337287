"""Reading a finished MCAP file through its summary's chunk index, every chunk checked."""

from __future__ import annotations

import io
import struct
from collections.abc import Iterator
from typing import IO, Any

from analyzer.mcapio.read.file_end import MAGIC, data_section_crc
from analyzer.mcapio.read.records import (
    MAX_RECORD,
    MESSAGE_FIXED,
    OPCODE_CHUNK,
    OPCODE_MESSAGE,
    OPCODE_METADATA,
    RECORD_HEAD,
    ChunkDamage,
    chunk_payload,
    walk,
)
from analyzer.mcapio.read.recover import Damage
from analyzer.mcapio.read.stored_message import RawMessage, ReadPosition

_MESSAGE_HEAD = struct.Struct("<HIQ")  # channel id, sequence, log time


def unique_chunk_indexes(summary: Any) -> list[Any]:
    """The summary's chunk indexes, each chunk once, in file order."""
    seen: set[int] = set()
    out = []
    indexes = [] if summary is None else summary.chunk_indexes
    for index in sorted(indexes, key=lambda i: i.chunk_start_offset):
        if index.chunk_start_offset not in seen:
            seen.add(index.chunk_start_offset)
            out.append(index)
    return out


def read_indexed(
    path: str,
    summary: Any,
    data_end: int,
    chosen: dict[int, tuple[str, str]],
    damaged_chunks: set[int],
    position: ReadPosition | None = None,
) -> Iterator[RawMessage | Damage]:
    """Messages of the ``chosen`` channels (id -> topic, role), reading only the chunks that
    hold them; a damaged chunk is skipped, its offset added to ``damaged_chunks``.
    ``position`` follows the end of the chunk read last."""
    indexes = [
        index
        for index in unique_chunk_indexes(summary)
        if not index.message_index_offsets or chosen.keys() & index.message_index_offsets
    ]
    with open(path, "rb") as f:
        for index in indexes:
            if position is not None:
                position.bytes = index.chunk_start_offset + index.chunk_length
            try:
                records = chunk_records(f, index, data_end)
                found = [
                    RawMessage(*chosen[channel_id], log_time, data)
                    for channel_id, log_time, data in messages_in(records)
                    if channel_id in chosen
                ]
            except ChunkDamage as exc:  # skip it, keep reading, tell the caller
                damaged_chunks.add(index.chunk_start_offset)
                yield Damage(
                    index.message_start_time,
                    f"damaged chunk at byte {index.chunk_start_offset} skipped: {exc}",
                )
                continue
            yield from found


def chunk_records(f: IO[bytes], index: Any, data_end: int) -> bytes:
    """The records of the chunk an index entry points to (ChunkDamage when unusable)."""
    offset, length = index.chunk_start_offset, index.chunk_length
    if not len(MAGIC) <= offset < offset + length <= data_end or length > MAX_RECORD:
        raise ChunkDamage("its index entry points outside the data section")
    f.seek(offset)
    raw = f.read(length)
    if len(raw) < 9 or raw[0] != OPCODE_CHUNK:
        raise ChunkDamage("no chunk where its index entry points")
    if RECORD_HEAD.unpack_from(raw)[1] != length - 9:
        raise ChunkDamage("its record length does not match its index entry")
    return chunk_payload(memoryview(raw)[9:])


def messages_in(records: bytes) -> Iterator[tuple[int, int, bytes]]:
    """(channel id, log time, data) of every message in a chunk's records."""
    unpack = _MESSAGE_HEAD.unpack_from
    for opcode, body, end in walk(records):
        if opcode == OPCODE_MESSAGE:
            if end - body < MESSAGE_FIXED:
                raise ChunkDamage("a message record is too short")
            channel_id, _, log_time = unpack(records, body)
            yield channel_id, log_time, records[body + MESSAGE_FIXED : end]


def indexed_metadata(f: IO[bytes], summary: Any, data_end: int) -> dict[str, dict[str, str]]:
    """Metadata records by name, found through the summary's metadata index (an index entry
    pointing outside the data is ignored; a damaged record ends the search)."""
    from mcap.data_stream import ReadDataStream
    from mcap.records import Metadata

    out: dict[str, dict[str, str]] = {}
    try:
        for index in summary.metadata_indexes:
            if not 0 < index.offset <= index.offset + index.length <= data_end:
                continue
            f.seek(index.offset)
            raw = f.read(index.length)
            if len(raw) < 9 or raw[0] != OPCODE_METADATA:
                continue
            found = Metadata.read(ReadDataStream(io.BytesIO(raw[9:])))
            out[found.name] = dict(found.metadata)
    except Exception:  # keep what was found before the damaged record
        pass
    return out


def verify_chunks(
    path: str, summary: Any, summary_start: int, data_end: int, damaged_chunks: set[int]
) -> list[Damage]:
    """Check every chunk of a finished file not in ``damaged_chunks`` (the data section CRC
    first: when it matches, nothing else is read); the damaged ones found are added there."""
    found: list[Damage] = []
    with open(path, "rb") as f:
        stored = data_section_crc(f, summary_start)
        if stored is not None and stored[0] and stored[0] == stored[1]:
            return []
        for index in unique_chunk_indexes(summary):
            if index.chunk_start_offset in damaged_chunks:
                continue
            try:
                chunk_records(f, index, data_end)
            except ChunkDamage as exc:
                damaged_chunks.add(index.chunk_start_offset)
                found.append(
                    Damage(
                        index.message_start_time,
                        f"damaged chunk at byte {index.chunk_start_offset}: {exc}",
                    )
                )
    if not found and not damaged_chunks and stored is not None and stored[0]:
        found.append(
            Damage(
                0,
                "the data section fails its CRC check outside the chunks (an index "
                "or metadata record is damaged; the messages are intact)",
            )
        )
    return found
