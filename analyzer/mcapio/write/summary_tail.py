"""The end of an MCAP file: data end, summary groups, summary offsets, footer and magic."""

from __future__ import annotations

import struct
import zlib

from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import DataEnd, Footer, SummaryOffset

MAGIC = b"\x89MCAP0\r\n"


def serialise(record: object) -> bytes:
    """One record (an ``mcap.records`` object) as bytes, by the mcap library's own code."""
    builder = RecordBuilder()
    record.write(builder)  # type: ignore[attr-defined]
    return bytes(builder.end())


def summary_tail(data_end: int, data_crc: int, groups: list[tuple[Opcode, list[bytes]]]) -> bytes:
    """Everything after a data section ending at ``data_end`` (its CRC ``data_crc``): the
    DataEnd record, the summary of ``groups`` (opcode, serialised records; empty groups left
    out) with a summary offset per group, the footer with the summary CRC, the magic."""
    data_end_record = serialise(DataEnd(data_section_crc=data_crc))
    summary_start = data_end + len(data_end_record)
    parts: list[bytes] = []
    offsets: list[SummaryOffset] = []
    position = summary_start
    for opcode, records in groups:
        if not records:
            continue
        size = sum(len(r) for r in records)
        offsets.append(SummaryOffset(group_opcode=opcode, group_start=position, group_length=size))
        parts.extend(records)
        position += size
    summary_offset_start = position
    parts.extend(serialise(o) for o in offsets)
    summary = b"".join(parts)
    crc = zlib.crc32(summary)
    crc = zlib.crc32(
        struct.pack("<BQQQ", Opcode.FOOTER, 8 + 8 + 4, summary_start, summary_offset_start),
        crc,
    )
    footer = Footer(
        summary_start=summary_start,
        summary_offset_start=summary_offset_start,
        summary_crc=crc,
    )
    return data_end_record + summary + serialise(footer) + MAGIC
