"""MCAP records from untrusted bytes: bounded chunk decompression, CRC checks, resync search."""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from typing import IO

# Limits for hostile files: a chunk that claims more is refused, not allocated. This
# project writes 128 KiB chunks; other writers use a few MiB.
MAX_CHUNK_UNCOMPRESSED = 64 * 1024 * 1024
MAX_RECORD = MAX_CHUNK_UNCOMPRESSED + 1024
COMPRESSIONS = ("", "zstd", "lz4")

OPCODE_HEADER = 0x01
OPCODE_FOOTER = 0x02
OPCODE_SCHEMA = 0x03
OPCODE_CHANNEL = 0x04
OPCODE_MESSAGE = 0x05
OPCODE_CHUNK = 0x06
OPCODE_MESSAGE_INDEX = 0x07
OPCODE_ATTACHMENT = 0x09
OPCODE_METADATA = 0x0C
OPCODE_DATA_END = 0x0F
# Records that may stand in the data section between chunks.
DATA_OPCODES = frozenset(
    {
        OPCODE_HEADER,
        OPCODE_SCHEMA,
        OPCODE_CHANNEL,
        OPCODE_MESSAGE,
        OPCODE_CHUNK,
        OPCODE_MESSAGE_INDEX,
        OPCODE_ATTACHMENT,
        OPCODE_METADATA,
        OPCODE_DATA_END,
    }
)

RECORD_HEAD = struct.Struct("<BQ")  # opcode, body length
_CHUNK_FIXED = struct.Struct("<QQQII")  # start, end, uncompressed size, crc, compression len
_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")
MESSAGE_FIXED = 2 + 4 + 8 + 8  # channel id, sequence, log time, publish time
_WINDOW = 1 << 20  # resync search reads the file in windows this large


class ChunkDamage(ValueError):
    """A chunk that cannot be used; the message says why in words."""


@dataclass(frozen=True, slots=True)
class ChunkHead:
    """The fixed fields of a chunk record and where its data lies inside the record body."""

    start_time: int
    end_time: int
    uncompressed_size: int
    crc: int
    compression: str
    data_offset: int
    data_length: int
    refused: str = ""  # well framed, but not to be decompressed: why


def parse_chunk(body: bytes | memoryview) -> ChunkHead:
    """The head of a chunk record body; ChunkDamage unless every length is consistent.
    A well-framed chunk that must not be decompressed (too large, unknown compression)
    says why in ``refused``."""
    if len(body) < _CHUNK_FIXED.size + 8:
        raise ChunkDamage("the chunk record is too short")
    start, end, size, crc, name_length = _CHUNK_FIXED.unpack_from(body, 0)
    if name_length > 16:
        raise ChunkDamage("the chunk's compression name is garbled")
    at = _CHUNK_FIXED.size
    try:
        compression = bytes(body[at : at + name_length]).decode("ascii")
    except UnicodeDecodeError:
        raise ChunkDamage("the chunk's compression name is garbled") from None
    at += name_length
    if len(body) < at + 8:
        raise ChunkDamage("the chunk record is too short")
    (data_length,) = _U64.unpack_from(body, at)
    at += 8
    if at + data_length != len(body):
        raise ChunkDamage("the chunk's data length does not match its record length")
    refused = ""
    if compression not in COMPRESSIONS:
        refused = f"unknown compression {compression!r}"
    elif size > MAX_CHUNK_UNCOMPRESSED:
        refused = (
            f"the chunk claims {size} bytes uncompressed, more than the limit of "
            f"{MAX_CHUNK_UNCOMPRESSED} (refused)"
        )
    return ChunkHead(start, end, size, crc, compression, at, data_length, refused)


def decompress(data: bytes | memoryview, compression: str, size: int) -> bytes:
    """Decompress at most ``size`` bytes; ChunkDamage when the result is not exactly that."""
    if compression == "":
        out = bytes(data)
    elif compression == "zstd":
        import zstandard

        try:
            reader = zstandard.ZstdDecompressor().stream_reader(
                bytes(data), read_across_frames=True
            )
            out = reader.read(size + 1)  # bounded: a bomb stops one byte past the claim
        except zstandard.ZstdError as exc:
            raise ChunkDamage(f"zstd decompression failed ({exc})") from None
    else:
        import lz4.frame

        try:
            out = lz4.frame.LZ4FrameDecompressor().decompress(bytes(data), max_length=size + 1)
        except RuntimeError as exc:
            raise ChunkDamage(f"lz4 decompression failed ({exc})") from None
    if len(out) != size:
        what = "more" if len(out) > size else f"{len(out)}"
        raise ChunkDamage(f"the chunk decompresses to {what} bytes, not the {size} it claims")
    return out


def chunk_payload(body: bytes | memoryview, head: ChunkHead | None = None) -> bytes:
    """The records of a chunk, decompressed and CRC-checked (ChunkDamage otherwise)."""
    head = parse_chunk(body) if head is None else head
    if head.refused:
        raise ChunkDamage(head.refused)
    data = memoryview(body)[head.data_offset : head.data_offset + head.data_length]
    out = decompress(data, head.compression, head.uncompressed_size)
    if head.crc and zlib.crc32(out) != head.crc:
        raise ChunkDamage("the chunk fails its CRC check")
    return out


def walk(data: bytes) -> Iterator[tuple[int, int, int]]:
    """(opcode, body start, end) of every record in a chunk's records."""
    pos, size = 0, len(data)
    unpack = RECORD_HEAD.unpack_from
    while pos < size:
        if pos + 9 > size:
            raise ChunkDamage("the chunk ends inside a record head")
        opcode, length = unpack(data, pos)
        end = pos + 9 + length
        if end > size:
            raise ChunkDamage("a record runs past the end of its chunk")
        yield opcode, pos + 9, end
        pos = end


def plausible_record(opcode: int, body: bytes) -> bool:
    """Whether a record outside chunks is well formed (used to tell data from garbage)."""
    if opcode not in DATA_OPCODES:
        return False
    if opcode == OPCODE_CHUNK:
        try:
            parse_chunk(body)
        except ChunkDamage:
            return False
        return True
    if opcode == OPCODE_MESSAGE:
        return len(body) >= MESSAGE_FIXED
    if opcode == OPCODE_MESSAGE_INDEX:
        if len(body) < 6:
            return False
        (pairs,) = _U32.unpack_from(body, 2)
        return 6 + pairs == len(body) and pairs % 16 == 0
    if opcode == OPCODE_DATA_END:
        return len(body) == 4
    return _parses(opcode, body)


def _parses(opcode: int, body: bytes) -> bool:
    import io

    from mcap.data_stream import ReadDataStream
    from mcap.records import Attachment, Channel, Header, Metadata, Schema

    kinds = {
        OPCODE_HEADER: Header,
        OPCODE_SCHEMA: Schema,
        OPCODE_CHANNEL: Channel,
        OPCODE_ATTACHMENT: Attachment,
        OPCODE_METADATA: Metadata,
    }
    stream = ReadDataStream(io.BytesIO(body))
    try:
        kinds[opcode].read(stream)  # type: ignore[attr-defined]
    except Exception:  # any parse failure means: not this record
        return False
    return stream.count == len(body)


def find_chunk(f: IO[bytes], start: int, stop: int) -> int | None:
    """Offset of the first chunk at or after ``start`` (before ``stop``) that is intact:
    its lengths agree and its data passes decompression and its CRC. None if there is none."""
    pos = start
    while pos + 9 < stop:
        f.seek(pos)
        window = f.read(min(_WINDOW, stop - pos))
        hit = window.find(b"\x06")
        while hit >= 0:
            candidate = pos + hit
            if _intact_chunk_at(f, candidate, stop):
                return candidate
            hit = window.find(b"\x06", hit + 1)
        pos += max(1, len(window) - 8)
        if not window:
            break
    return None


def _intact_chunk_at(f: IO[bytes], offset: int, stop: int) -> bool:
    f.seek(offset)
    head = f.read(9 + _CHUNK_FIXED.size + 16 + 8)
    if len(head) < 9 + _CHUNK_FIXED.size + 8:
        return False
    opcode, length = RECORD_HEAD.unpack_from(head, 0)
    if opcode != OPCODE_CHUNK or length > MAX_RECORD or offset + 9 + length > stop:
        return False
    size = _CHUNK_FIXED.unpack_from(head, 9)[2]
    if size > MAX_CHUNK_UNCOMPRESSED:
        return False
    f.seek(offset + 9)
    body = f.read(length)
    try:
        chunk_payload(body)
    except ChunkDamage:
        return False
    return True
