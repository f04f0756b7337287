"""Opening an MCAP file: its magic, footer and summary, each checked before it is believed."""

from __future__ import annotations

import io
import os
import struct
import zlib
from dataclasses import dataclass
from typing import IO, Any

from analyzer.errors import InputError
from analyzer.mcapio.read.records import OPCODE_DATA_END, RECORD_HEAD

MAGIC = b"\x89MCAP0\r\n"
FOOTER_RECORD_SIZE = 1 + 8 + 8 + 8 + 4  # opcode, length, summary start, offset start, crc
_FOOTER = struct.Struct("<BQQQI")
OPCODE_FOOTER = 0x02


class RecordingError(InputError):
    """The file is not an MCAP recording, or is damaged beyond its readable part (exit 2)."""


@dataclass
class FileEnd:
    """What the ends of a file say: its size, its summary (when believed) and what is wrong."""

    size: int
    damaged_magic: bool  # the leading magic is damaged, the closing one is there
    problem: str  # '' when the footer and summary can be believed, else why not
    summary_start: int  # 0 when the footer is missing, invalid or names no summary
    summary: Any  # the mcap Summary; None without one or when it was not believed


def read_file_end(path: str) -> FileEnd:
    """Check the magic, footer and summary of ``path`` (RecordingError when not an MCAP)."""
    try:
        size = os.path.getsize(path)
        with open(path, "rb") as f:
            head = f.read(len(MAGIC))
            damaged_magic = head != MAGIC and _ends_with_magic(f, size)
            if head != MAGIC and not damaged_magic:
                what = "an empty file" if not head else "not an MCAP file"
                raise RecordingError(f"{path}: {what}")
            problem, start, crc = _check_end(f, size)
            summary = None
            if not problem:
                problem, summary = _load_summary(f, size, start, crc)
    except OSError as exc:
        raise RecordingError(f"cannot read {path}: {exc.strerror or exc}") from None
    return FileEnd(size, damaged_magic, problem, start, summary)


def read_header(path: str) -> tuple[str, str]:
    """(profile, library) of the file's header record; ('', '') when it cannot be read."""
    with open(path, "rb") as f:
        head = f.read(len(MAGIC) + 9 + 1024)
    at = len(MAGIC)
    if len(head) < at + 9 or head[at] != 0x01:
        return "", ""
    out = []
    at += 9
    for _ in range(2):
        if at + 4 > len(head):
            return "", ""
        (length,) = struct.unpack_from("<I", head, at)
        text = head[at + 4 : at + 4 + length]
        if len(text) < length:
            return "", ""
        out.append(text.decode("utf-8", "replace"))
        at += 4 + length
    return out[0], out[1]


def _ends_with_magic(f: IO[bytes], size: int) -> bool:
    if size < 2 * len(MAGIC) + FOOTER_RECORD_SIZE:
        return False
    f.seek(-len(MAGIC), os.SEEK_END)
    return f.read(len(MAGIC)) == MAGIC


def _check_end(f: IO[bytes], size: int) -> tuple[str, int, int]:
    """('', summary start, summary CRC) when the file ends with a footer and magic, else
    (what is missing, 0, 0)."""
    if size < 2 * len(MAGIC) + FOOTER_RECORD_SIZE:
        return "the file has no footer (recording not finished)", 0, 0
    f.seek(-len(MAGIC), os.SEEK_END)
    if f.read(len(MAGIC)) != MAGIC:
        return "the file has no footer (recording not finished)", 0, 0
    f.seek(-(len(MAGIC) + FOOTER_RECORD_SIZE), os.SEEK_END)
    footer = f.read(FOOTER_RECORD_SIZE)
    opcode, length, start, _, crc = _FOOTER.unpack(footer)
    if opcode != OPCODE_FOOTER or length != 20:
        return "the file has no valid footer", 0, 0
    footer_at = size - len(MAGIC) - FOOTER_RECORD_SIZE
    if start and not len(MAGIC) < start <= footer_at:
        return "the footer points outside the file", 0, 0
    return "", start, crc


def _load_summary(f: IO[bytes], size: int, start: int, crc: int) -> tuple[str, Any]:
    """Read and check the summary section: ('', summary) when it can be believed (summary
    None when the file has none), else (why not, None)."""
    if not start:
        return "", None
    footer_at = size - len(MAGIC) - FOOTER_RECORD_SIZE
    f.seek(start)
    section = f.read(footer_at - start)
    f.seek(footer_at)
    footer = f.read(FOOTER_RECORD_SIZE)
    if crc and zlib.crc32(footer[:-4], zlib.crc32(section)) != crc:
        return (
            "the summary section fails its CRC check, so its statistics and index are not used",
            None,
        )
    try:
        return "", parse_summary(section + footer + MAGIC)
    except Exception as exc:  # any parse failure of the summary means: read sequentially
        return f"the summary is unreadable ({_why(exc)})", None


def parse_summary(section: bytes) -> Any:
    """The records of a summary section (already CRC-checked, followed by the footer and
    the closing magic) as an mcap Summary."""
    from mcap.records import (
        AttachmentIndex,
        Channel,
        ChunkIndex,
        MetadataIndex,
        Schema,
        Statistics,
    )
    from mcap.stream_reader import StreamReader
    from mcap.summary import Summary

    summary = Summary()
    reader = StreamReader(io.BytesIO(section), skip_magic=True, record_size_limit=len(section))
    for record in reader.records:
        if isinstance(record, Statistics):
            summary.statistics = record
        elif isinstance(record, Schema):
            summary.schemas[record.id] = record
        elif isinstance(record, Channel):
            summary.channels[record.id] = record
        elif isinstance(record, ChunkIndex):
            summary.chunk_indexes.append(record)
        elif isinstance(record, MetadataIndex):
            summary.metadata_indexes.append(record)
        elif isinstance(record, AttachmentIndex):
            summary.attachment_indexes.append(record)
    return summary


def data_section_crc(f: IO[bytes], summary_start: int) -> tuple[int, int] | None:
    """(stored, computed) CRC of the data section, None when there is no DataEnd."""
    end = summary_start - (9 + 4)
    if end < len(MAGIC):
        return None
    f.seek(end)
    record = f.read(13)
    opcode, length = RECORD_HEAD.unpack_from(record)
    if opcode != OPCODE_DATA_END or length != 4:
        return None
    stored = int.from_bytes(record[9:13], "little")
    crc, f_pos = 0, 0
    f.seek(0)
    while f_pos < end:
        block = f.read(min(1 << 20, end - f_pos))
        if not block:
            break
        crc = zlib.crc32(block, crc)
        f_pos += len(block)
    return stored, crc


def _why(exc: BaseException) -> str:
    text = str(exc)
    name = type(exc).__name__
    if name == "EndOfFile" or not text:
        return "end of file inside a record (recording not finished)"
    return f"{name}: {text}"
