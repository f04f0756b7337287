"""A Python counterpart of the checks `mcap doctor` makes, for recordings made in tests."""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import lz4.frame
import zstandard
from mcap.records import Channel, Chunk, ChunkIndex, DataEnd, Footer, Message, MessageIndex, Schema
from mcap.stream_reader import StreamReader, breakup_chunk


@dataclass
class Diagnosis:
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    chunks: int = 0
    messages: int = 0
    compressions: set[str] = field(default_factory=set)


def breakup_chunk_records(data: bytes) -> list[tuple[int, Message | Schema | Channel]]:
    """Records of an uncompressed chunk, each with its offset inside the chunk."""
    out: list[tuple[int, Message | Schema | Channel]] = []
    position = 0
    while position < len(data):
        _, length = struct.unpack_from("<BQ", data, position)
        record_bytes = data[position : position + 9 + length]
        fake_chunk = Chunk(
            compression="",
            data=record_bytes,
            message_start_time=0,
            message_end_time=0,
            uncompressed_crc=0,
            uncompressed_size=len(record_bytes),
        )
        (record,) = breakup_chunk(fake_chunk, validate_crc=False)
        out.append((position, record))
        position += 9 + length
    return out


def _records(reader: StreamReader, error: Callable[[str], None]) -> Iterator[object]:
    """The records of a file; a file cut short (a killed recorder) ends them with an error."""
    records = iter(reader.records)
    while True:
        try:
            yield next(records)
        except StopIteration:
            return
        except Exception as exc:  # the half-written tail of a killed recorder
            error(f"file ends inside a record: {type(exc).__name__}: {exc}")
            return


def examine(path: Path) -> Diagnosis:
    """Walk the file in order like `mcap doctor`: chunks, their messages, indexes, times."""
    diagnosis = Diagnosis()
    error, warn = diagnosis.errors.append, diagnosis.warnings.append
    channels: dict[int, Channel] = {}
    max_log_time = 0
    last_chunk: Chunk | None = None
    last_indexes: dict[int, MessageIndex] = {}
    chunk_indexes: list[ChunkIndex] = []
    saw_data_end = saw_footer = False

    def examine_chunk(chunk: Chunk, indexes: dict[int, MessageIndex]) -> None:
        nonlocal max_log_time
        diagnosis.chunks += 1
        diagnosis.compressions.add(chunk.compression)
        if chunk.compression == "zstd":
            data = zstandard.decompress(chunk.data, chunk.uncompressed_size)
        elif chunk.compression == "lz4":
            data = lz4.frame.decompress(chunk.data)
        elif chunk.compression == "":
            data = chunk.data
        else:
            error(f"unsupported compression format {chunk.compression!r}")
            return
        if len(data) != chunk.uncompressed_size:
            error("uncompressed chunk data size != Chunk.uncompressed_size")
            return
        if chunk.uncompressed_crc and zlib.crc32(data) != chunk.uncompressed_crc:
            error("invalid chunk CRC")
            return
        lo, hi, count = 2**64, 0, 0
        for offset, record in breakup_chunk_records(data):
            if isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message):
                topic = channels[record.channel_id].topic if record.channel_id in channels else "?"
                if record.channel_id not in channels:
                    error(f"message on channel {record.channel_id} before its channel record")
                if record.log_time < max_log_time:
                    warn(
                        f"Message.log_time {record.log_time} on {topic!r} is less than the "
                        f"latest log time {max_log_time}"
                    )
                max_log_time = max(max_log_time, record.log_time)
                lo, hi, count = min(lo, record.log_time), max(hi, record.log_time), count + 1
                index = indexes.get(record.channel_id)
                if index is None:
                    warn(f"no MessageIndex record for channel {record.channel_id}")
                else:
                    times = {o: t for t, o in index.records}
                    if offset not in times:
                        warn(f"no MessageIndex entry for a message of channel {record.channel_id}")
                    elif times[offset] != record.log_time:
                        error(f"MessageIndex entry at {offset} has the wrong timestamp")
        diagnosis.messages += count
        if count:
            if lo != chunk.message_start_time:
                error(f"Chunk.message_start_time {chunk.message_start_time} != earliest {lo}")
            if hi != chunk.message_end_time:
                error(f"Chunk.message_end_time {chunk.message_end_time} != latest {hi}")

    with path.open("rb") as f:
        for record in _records(StreamReader(f, skip_magic=False, emit_chunks=True), error):
            if not isinstance(record, MessageIndex) and last_chunk is not None:
                examine_chunk(last_chunk, last_indexes)
                last_chunk, last_indexes = None, {}
            if isinstance(record, Chunk):
                last_chunk = record
            elif isinstance(record, MessageIndex):
                if last_chunk is None:
                    error("message index found but no chunk before it")
                last_indexes[record.channel_id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message):
                error("message outside a chunk")
            elif isinstance(record, ChunkIndex):
                chunk_indexes.append(record)
            elif isinstance(record, DataEnd):
                saw_data_end = True
            elif isinstance(record, Footer):
                saw_footer = True
    if last_chunk is not None:
        examine_chunk(last_chunk, last_indexes)
    if not saw_data_end:
        error("no DataEnd record")
    if not saw_footer:
        error("no Footer record")
    if chunk_indexes and len(chunk_indexes) != diagnosis.chunks:
        error(f"{len(chunk_indexes)} chunk indexes for {diagnosis.chunks} chunks")
    return diagnosis
