"""ArduPilot DataFlash logs (.bin): the CAN frames of CANF / CAFD records, on UTC from GPS time.

ArduPilot logs every CAN frame of a bus whose ``CAN_Px_OPTIONS`` has LogAllFrames as a
``CANF`` record (``CAFD`` for CAN FD); a Lua script logging frames writes its own
``CANF`` with other columns. Records are found by the column names their FMT record
gives (message ids differ from build to build), walked directly with one precompiled
struct per layout. ``TimeUS`` counts from boot: the first GPS record with a week
number puts it on UTC (leap seconds included); without one the times stay since boot.
Damage (bytes that are no record, a record cut short) is reported with its byte
offset and reading resynchronises at the next ``A3 95`` that starts a known record.
"""

from __future__ import annotations

import mmap
from collections.abc import Iterator
from dataclasses import dataclass

from analyzer.inputs.base import InputItem, InputReader
from analyzer.inputs.dataflash.formats import (
    FMT_LENGTH,
    FMT_TYPE,
    HEAD,
    CanColumns,
    RecordLayout,
    can_columns,
    parse_fmt,
)
from analyzer.inputs.dataflash.gps_time import gps_to_utc
from analyzer.inputs.textlines import GZIP_MAGIC, open_lines
from analyzer.protocol.types import BAD_FRAME, CanFrame, Event, diagnostic

# AP_HAL::CANFrame flags in the ID word (libraries/AP_HAL/CANIface.h).
FLAG_EFF, FLAG_RTR, FLAG_ERR = 1 << 31, 1 << 30, 1 << 29
MASK_EXT = 0x1FFFFFFF
FD_LENGTHS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)  # CAN FD DLC -> bytes
PADDING = frozenset({0x00, 0xFF})  # what the unwritten rest of a block log holds
PROGRESS_EVERY = 0x3FFF  # records between position updates
SINCE_BOOT = "time since the autopilot booted (the log holds no GPS time)"
GPS_UTC = "UTC from the log's GPS time (GPS week and milliseconds, leap seconds applied)"


@dataclass
class DataFlashStats:
    records: int = 0
    can_records: int = 0
    fd_records: int = 0
    formats: int = 0
    damaged_spots: int = 0
    bytes_skipped: int = 0


class DataFlashReader(InputReader):
    """CAN frames of an ArduPilot DataFlash log; channel ``bus<N>`` from the record's Bus
    (``scripting`` for a Lua script's CANF, which has none)."""

    format_name = "dataflash"

    def __init__(self, path: str) -> None:
        super().__init__(path)
        handle = self._open_binary()
        size = self.size_bytes or 0
        self._gzip_problems: list[str] = []
        self._data: bytes | mmap.mmap = b""
        if handle.read(2) == GZIP_MAGIC:  # a .BIN.gz: unpacked in memory, damage reported
            handle.seek(0)
            blocks, self._gzip_problems = open_lines(handle)
            self._data = b"".join(blocks)
        elif size:
            self._data = mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_READ)
            self._closers.append(self._data)
        self.counts = DataFlashStats()
        self._unread_layouts: dict[int, tuple[str, str]] = {}  # CAN layouts not understood
        self._unread_records: dict[int, int] = {}  # their records, by type
        self._channels: dict[int, str] = {}  # the name of each bus number
        self.time_offset = self._find_time_base()
        self.time_base = GPS_UTC if self.time_offset is not None else SINCE_BOOT
        if self.time_offset is None:
            self.notes.append(
                f"{self.source} holds no GPS record with a GPS week: frame times are "
                "seconds since the autopilot booted, not dates"
            )

    def __iter__(self) -> Iterator[InputItem]:
        """Every record in turn: CAN records as frames, FMT records taken in, damage said
        and skipped to the next record. This loop runs for every record of a log
        (benchmarks/dataflash_speed.py): the usual record costs one look-up and one call."""
        data = self._data
        size = len(data)
        base = self.time_offset or 0.0
        lengths: dict[int, int] = {FMT_TYPE: FMT_LENGTH}
        cans: dict[int, CanColumns] = {}
        frame = self._frame
        pos = records = frames = 0
        while pos < size:
            kind = data[pos + 2] if pos + 2 < size else -1
            length = lengths.get(kind, 0) if data[pos : pos + 2] == HEAD else 0
            end = pos + length
            if not length or end > size:
                found = self._resync(pos, lengths)
                yield from self._damage(pos, found, size, kind, length, base, records)
                if found is None:
                    break
                pos = found
                continue
            records += 1
            if not records & PROGRESS_EVERY:
                self.position_bytes = pos
            columns = cans.get(kind)
            if columns is None:
                self._other_record(kind, pos, lengths, cans)
            elif (
                end < size
                and data[end : end + 2] != HEAD
                and ((found := self._inside(pos, end, lengths)) is not None)
            ):  # damage inside this record
                yield from self._damage(pos, found, size, kind, length, base, records)
                pos = found
                continue
            else:
                frames += 1
                yield frame(columns, pos, base)
            pos = end
        self.counts.records = records
        self.counts.can_records = frames
        yield from self._finished(self.last_time or base)

    def _other_record(
        self, kind: int, pos: int, lengths: dict[int, int], cans: dict[int, CanColumns]
    ) -> None:
        """A record that is no CAN frame: a format taken in, one not understood counted."""
        if kind == FMT_TYPE:
            self._define(parse_fmt(self._data, pos), lengths, cans)
        elif kind in self._unread_records:
            self._unread_records[kind] += 1

    def _inside(self, pos: int, end: int, lengths: dict[int, int]) -> int | None:
        """Where a record starts inside the one at ``pos``, which no record follows (None:
        nowhere, the record is whole)."""
        found = self._resync(pos + 3, lengths)
        return found if found is not None and found < end else None

    def _frame(self, columns: CanColumns, pos: int, base: float) -> InputItem:
        """The CAN record at ``pos`` as a frame (a diagnostic for a DLC over 8)."""
        values = columns.fields.unpack_from(self._data, pos + 3)
        if columns.order is not None:
            values = tuple(values[i] for i in columns.order)
        if columns.has_bus:
            time_us, bus, ident, dlc = values
            channels = self._channels
            channel = channels.get(bus) or channels.setdefault(bus, f"bus{bus}")
        else:
            time_us, ident, dlc = values
            channel = "scripting"
        time = self.last_time = base + time_us * 1e-6
        if self.first_time is None:
            self.first_time = time
        if columns.fd:
            self.counts.fd_records += 1
            dlc = FD_LENGTHS[dlc & 0x0F]
        elif dlc > 8:
            return self._bad_dlc(pos, time, ident, dlc)
        if ident & FLAG_RTR:
            return CanFrame(
                time, ident & MASK_EXT, b"", bool(ident & FLAG_EFF), channel, True,
                bool(ident & FLAG_ERR), columns.fd, "", dlc,
            )  # fmt: skip
        at = pos + columns.data_at
        return CanFrame(
            time, ident & MASK_EXT, self._data[at : at + dlc], bool(ident & FLAG_EFF), channel,
            False, bool(ident & FLAG_ERR), columns.fd,
        )  # fmt: skip

    def _finished(self, last_time: float) -> Iterator[InputItem]:
        """After the last record: what the decompression found wrong, as diagnostics, and
        the records of a layout that could not be read as CAN frames, as notes."""
        for problem in self._gzip_problems:
            yield diagnostic(last_time, self.source, BAD_FRAME, problem)
        for kind, count in self._unread_records.items():
            name, why = self._unread_layouts[kind]
            self.notes.append(
                f"{count:,} {name} record(s) (type {kind}) could not be read as CAN frames: {why}"
            )
        self.position_bytes = self.size_bytes or 0

    def _define(
        self, layout: RecordLayout | None, lengths: dict[int, int], cans: dict[int, CanColumns]
    ) -> None:
        """Take a new record format in: its length, and its CAN columns if it is CANF/CAFD."""
        if layout is None:
            return
        self.counts.formats += 1
        lengths[layout.type] = layout.length
        column = can_columns(layout)
        cans.pop(layout.type, None)
        if isinstance(column, CanColumns):
            cans[layout.type] = column
        elif column is not None:  # a CANF / CAFD this reader does not understand
            self._unread_layouts[layout.type] = (layout.name, column)
            self._unread_records.setdefault(layout.type, 0)

    def _bad_dlc(self, pos: int, time: float, ident: int, dlc: int) -> Event:
        return diagnostic(
            time,
            self.source,
            BAD_FRAME,
            f"CANF record at byte {pos:,} has a DLC of {dlc} (at most 8): skipped",
            bytes(self._data[pos : pos + 24]),
            can_id=ident & MASK_EXT,
        )

    def _resync(self, start: int, lengths: dict[int, int]) -> int | None:
        """The next offset after ``start`` where a known record begins and is followed by
        another record or the end of the file; None when there is none."""
        data = self._data
        size = len(data)
        at = data.find(HEAD, start + 1)
        while at >= 0:
            length = lengths.get(data[at + 2] if at + 2 < size else -1, 0)
            end = at + length
            if length and (end == size or (end < size and data[end : end + 2] == HEAD)):
                return at
            at = data.find(HEAD, at + 1)
        return None

    def _damage(
        self,
        pos: int,
        found: int | None,
        size: int,
        kind: int,
        length: int,
        base: float,
        records: int,
    ) -> list[Event]:
        data = self._data
        counts = self.counts
        stop = size if found is None else found
        skipped = stop - pos
        time = self.last_time if self.last_time is not None else base
        if found is None and set(data[pos:size]) <= PADDING:
            self.notes.append(
                f"{skipped:,} byte(s) of padding after the last record (an unwritten "
                "block of the log): ignored"
            )
            return []
        counts.damaged_spots += 1
        counts.bytes_skipped += skipped
        if data[pos : pos + 2] == HEAD and length and pos + length > size:
            what = (
                f"the file ends inside a record of type {kind} at byte {pos:,} "
                f"({size - pos} of its {length} bytes are there)"
            )
        elif data[pos : pos + 2] == HEAD and length:
            what = (
                f"the record of type {kind} at byte {pos:,} is cut short by damage "
                "(the next record starts inside it)"
            )
        else:
            what = f"the bytes at byte {pos:,} are no record (damage after record {records})"
        where = (
            "reading stopped"
            if found is None
            else f"{skipped:,} byte(s) skipped to the next record at byte {found:,}"
        )
        return [
            diagnostic(
                time,
                self.source,
                BAD_FRAME,
                f"DataFlash log damaged: {what}; {where}",
                bytes(data[pos : pos + min(skipped, 64)]),
                offset=pos,
                skipped_bytes=skipped,
            )
        ]

    def _find_time_base(self) -> float | None:
        """UTC minus TimeUS of the first GPS record with a week number (None if none).

        FMT and GPS records are found by searching for their header bytes, which is far
        quicker than walking every record; a candidate counts when a record follows it.
        """
        data = self._data
        size = len(data)
        at = data.find(HEAD + bytes([FMT_TYPE]))
        gps: RecordLayout | None = None
        while at >= 0 and gps is None:
            if at + FMT_LENGTH <= size:
                layout = parse_fmt(data, at)
                if layout is not None and layout.name == "GPS" and layout.body is not None:
                    gps = layout
            at = data.find(HEAD + bytes([FMT_TYPE]), at + 1)
        if gps is None:
            return None
        columns = [gps.index(c) for c in ("TimeUS", "GWk", "GMS")]
        if any(c is None for c in columns):
            return None
        time_i, week_i, ms_i = (c for c in columns if c is not None)
        marker = HEAD + bytes([gps.type])
        at = data.find(marker)
        while at >= 0:
            end = at + gps.length
            if end == size or (end < size and data[end : end + 2] == HEAD):
                values = gps.body.unpack_from(data, at + 3) if gps.body else ()
                if values and values[week_i] > 0:
                    return gps_to_utc(values[week_i], values[ms_i]) - values[time_i] * 1e-6
            at = data.find(marker, at + 1)
        return None

    @property
    def stats(self) -> dict[str, int]:
        return dict(vars(self.counts))


def looks_like_dataflash(head: bytes) -> bool:
    """Whether the first bytes of a file are a DataFlash log: it starts with FMT records."""
    if not head.startswith(HEAD + bytes([FMT_TYPE])) or len(head) < 89:
        return False
    layout = parse_fmt(head, 0)
    return layout is not None and (len(head) < 178 or head[89:91] == HEAD)
