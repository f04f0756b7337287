"""The records of pcap and pcapng files, read tolerantly: damage is described and skipped over.

A record with a wrong captured length, a pcapng block with an impossible length or a
file cut off in the middle of a record each becomes a ``Damage`` in words; reading
goes on at the next plausible record header, so one bad record does not swallow the
rest of the capture. Link types carry the FCS bits libpcap defines; they are masked
off as libpcap does, and the FCS length is kept so the FCS bytes can be cut off.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from typing import IO

PCAP_MAGICS = {
    b"\xd4\xc3\xb2\xa1": ("<", 1e-6),
    b"\xa1\xb2\xc3\xd4": (">", 1e-6),
    b"\x4d\x3c\xb2\xa1": ("<", 1e-9),
    b"\xa1\xb2\x3c\x4d": (">", 1e-9),
}
PCAPNG_MAGIC = b"\x0a\x0d\x0d\x0a"
BYTE_ORDER_MAGIC = 0x1A2B3C4D

LINKTYPE_MASK = 0x0000FFFF  # LT_LINKTYPE of libpcap
FCS_PRESENT = 0x04000000  # LT_FCS_LENGTH_PRESENT
MAX_PACKET = 1 << 18  # 256 KiB: libpcap's largest snapshot length
MAX_BLOCK = 1 << 24  # a pcapng block longer than 16 MiB is taken as damage
SCAN_LIMIT = 64 << 20  # bytes searched for the next record before giving up
CHUNK = 1 << 16
MAX_CLOCK_JUMP = 7 * 86400.0  # a record header this far from the last good time is garbage

# pcapng block types
SHB, IDB, OPB, SPB, EPB = 0x0A0D0D0A, 0x00000001, 0x00000002, 0x00000003, 0x00000006
KNOWN_BLOCKS = frozenset({SHB, IDB, OPB, SPB, EPB, 0x4, 0x5, 0xA, 0xBAD, 0x80000001})
IF_TSRESOL, IF_FCSLEN, IF_TSOFFSET = 9, 13, 14


@dataclass(slots=True)
class Packet:
    """One captured packet: time, link type (FCS bits masked), data, length on the wire."""

    time: float
    link: int
    data: bytes
    wire_length: int
    fcs_bytes: int = 0  # FCS at the end of ``data`` (when captured whole)

    @property
    def snapped(self) -> bool:
        """Captured shorter than it was on the wire (snap length)."""
        return len(self.data) < self.wire_length


@dataclass(slots=True)
class PcapDamage:
    """Something wrong with the file itself, in words, and the record it happened at."""

    text: str
    record: int


def split_link(value: int) -> tuple[int, int]:
    """A link type field -> (link type, FCS bytes), as libpcap reads it."""
    fcs = ((value >> 28) & 0xF) * 2 if value & FCS_PRESENT else 0
    return value & LINKTYPE_MASK, fcs


class CaptureFile:
    """Reads packets from a pcap or pcapng file opened for binary reading.

    Raises ValueError from the constructor when the file is not a capture at all.
    ``link`` is the link type of a pcap file (of the first interface of a pcapng one).
    """

    def __init__(self, handle: IO[bytes]) -> None:
        self._f = handle
        self.records = 0
        self.snaplen = MAX_PACKET
        magic = handle.read(4)
        self.ng = magic == PCAPNG_MAGIC
        self.link: int | None = None
        self.fcs_bytes = 0
        if self.ng:
            handle.seek(0)
            self._order = "<"
            self._interfaces: list[tuple[int, int, float, float]] = []
            return
        if magic not in PCAP_MAGICS:
            raise ValueError("not a pcap or pcapng file")
        self._order, self._unit = PCAP_MAGICS[magic]
        header = handle.read(20)
        if len(header) < 20:
            raise ValueError("the pcap file header is cut off")
        _major, _minor, _zone, _sigfigs, snaplen, link = struct.unpack(
            self._order + "HHiIII", header
        )
        self.link, self.fcs_bytes = split_link(link)
        self.snaplen = snaplen if 0 < snaplen <= MAX_PACKET else MAX_PACKET
        self._record = struct.Struct(self._order + "IIII")
        self._last_time: float | None = None

    def __iter__(self) -> Iterator[Packet | PcapDamage]:
        return self._pcapng() if self.ng else self._pcap()

    # -- pcap ------------------------------------------------------------------------------

    def _plausible(self, header: bytes) -> bool:
        sec, frac, caplen, wire = self._record.unpack(header)
        if caplen > MAX_PACKET or caplen > wire or wire > 4 * MAX_PACKET:
            return False
        if frac >= round(1 / self._unit):
            return False
        last = self._last_time
        return last is None or abs(sec - last) < MAX_CLOCK_JUMP

    def _pcap(self) -> Iterator[Packet | PcapDamage]:
        f = self._f
        size = self._record.size
        pos = 24
        while True:
            f.seek(pos)
            header = f.read(size)
            if not header:
                return
            if len(header) < size:
                yield PcapDamage(
                    f"the file is cut off inside the header of record {self.records + 1} "
                    f"(byte {pos:,})",
                    self.records,
                )
                return
            if not self._plausible(header):
                sec, _frac, caplen, wire = self._record.unpack(header)
                found = self._find_record(pos + 1)
                yield PcapDamage(self._skipped(pos, found, caplen, wire), self.records)
                if found is None:
                    return
                pos = found
                continue
            sec, frac, caplen, wire = self._record.unpack(header)
            data = f.read(caplen)
            end = pos + size + caplen
            following = f.read(size)
            if len(data) < caplen:
                self.records += 1
                yield PcapDamage(
                    f"the file is cut off inside record {self.records} (byte {pos:,}): "
                    f"{len(data)} of its {caplen} bytes are there",
                    self.records,
                )
                if data:
                    yield self._packet(sec, frac, data, wire)
                return
            if len(following) == size and not self._plausible(following):
                # What follows is no record header: this record's length is wrong, or
                # the next one is damaged. Take the nearest plausible header after this
                # one's start as the next record.
                found = self._find_record(pos + size)
                if found is not None and found < end:
                    self.records += 1
                    yield PcapDamage(
                        f"record {self.records} at byte {pos:,} has a wrong captured length "
                        f"({caplen} bytes, but the next record starts after "
                        f"{found - pos - size}): read up to there and resynchronised",
                        self.records,
                    )
                    yield self._packet(sec, frac, data[: found - pos - size], wire)
                    pos = found
                    continue
            self.records += 1
            yield self._packet(sec, frac, data, wire)
            pos = end

    def _packet(self, sec: int, frac: int, data: bytes, wire: int) -> Packet:
        time = sec + frac * self._unit
        self._last_time = sec
        assert self.link is not None
        return Packet(time, self.link, data, max(wire, len(data)), self.fcs_bytes)

    def _skipped(self, pos: int, found: int | None, caplen: int, wire: int) -> str:
        what = (
            f"the header of record {self.records + 1} at byte {pos:,} is damaged "
            f"(captured length {caplen}, length on the wire {wire})"
        )
        if found is None:
            return f"{what}: no further record could be found, reading stopped"
        return f"{what}: {found - pos:,} byte(s) skipped to the next record at byte {found:,}"

    def _find_record(self, start: int) -> int | None:
        """Offset of the next plausible record header from ``start`` on (None if none).

        A candidate must be followed by another plausible header or by the file's end.
        """
        f, size = self._f, self._record.size
        pos = start
        while pos - start < SCAN_LIMIT:
            f.seek(pos)
            block = f.read(CHUNK + 2 * size)
            if len(block) < size:
                return None
            for i in range(min(CHUNK, len(block) - size + 1)):
                header = block[i : i + size]
                if not self._plausible(header):
                    continue
                caplen = self._record.unpack(header)[2]
                f.seek(pos + i + size + caplen)
                after = f.read(size)
                if (not after and self._at_end(pos + i + size + caplen)) or (
                    len(after) == size and self._plausible(after)
                ):
                    return pos + i
            pos += CHUNK
        return None

    def _at_end(self, offset: int) -> bool:
        self._f.seek(0, 2)
        return self._f.tell() == offset

    # -- pcapng ----------------------------------------------------------------------------

    def _pcapng(self) -> Iterator[Packet | PcapDamage]:
        f = self._f
        pos = 0
        while True:
            f.seek(pos)
            head = f.read(8)
            if not head:
                return
            if len(head) < 8:
                yield PcapDamage(f"the file is cut off inside a block header at byte {pos:,}", 0)
                return
            if head[:4] == PCAPNG_MAGIC:
                order = f.read(4)
                if len(order) == 4:
                    self._order = ">" if order == b"\x1a\x2b\x3c\x4d" else "<"
                self._interfaces = []
            kind, length = struct.unpack(self._order + "II", head)
            problem = self._block_problem(pos, kind, length)
            if problem is None:
                f.seek(pos + 8)
                body = f.read(length - 8)
                if len(body) < length - 8:
                    yield PcapDamage(
                        f"the file is cut off inside a block at byte {pos:,} "
                        f"({len(body) + 8:,} of its {length:,} bytes are there)",
                        self.records,
                    )
                    return
                trailer = struct.unpack(self._order + "I", body[-4:])[0]
                if trailer != length:
                    problem = (
                        f"the block at byte {pos:,} says {length:,} bytes at its start but "
                        f"{trailer:,} at its end"
                    )
                else:
                    yield from self._block(kind, body[:-4])
                    pos += length
                    continue
            found = self._find_block(pos + 4)
            if found is None:
                yield PcapDamage(
                    f"{problem}: no further block found, reading stopped", self.records
                )
                return
            yield PcapDamage(
                f"{problem}: {found - pos:,} byte(s) skipped to the next block at byte {found:,}",
                self.records,
            )
            pos = found

    def _block_problem(self, pos: int, kind: int, length: int) -> str | None:
        if length < 12 or length % 4:
            return f"the block at byte {pos:,} has an impossible length ({length:,} bytes)"
        if length > MAX_BLOCK or pos + length > self._size():
            left = max(self._size() - pos, 0)
            return (
                f"the block at byte {pos:,} claims {length:,} bytes, more than the "
                f"{left:,} left in the file: the file is cut off or damaged there"
            )
        return None

    def _size(self) -> int:
        here = self._f.tell()
        self._f.seek(0, 2)
        size = self._f.tell()
        self._f.seek(here)
        return size

    def _find_block(self, start: int) -> int | None:
        """The next offset (4-aligned from ``start``) where a whole, known block begins."""
        f, size = self._f, self._size()
        pos = start
        fmt = self._order + "II"
        while pos < size and pos - start < SCAN_LIMIT:
            f.seek(pos)
            block = f.read(CHUNK + 8)
            for i in range(0, min(CHUNK, len(block) - 7), 4):
                kind, length = struct.unpack_from(fmt, block, i)
                if kind not in KNOWN_BLOCKS or length < 12 or length % 4 or length > MAX_BLOCK:
                    continue
                at = pos + i
                if at + length > size:
                    continue
                f.seek(at + length - 4)
                if struct.unpack(self._order + "I", f.read(4))[0] == length:
                    return at
            pos += CHUNK
        return None

    def _block(self, kind: int, body: bytes) -> Iterator[Packet | PcapDamage]:
        order = self._order
        if kind == IDB:
            if len(body) < 8:
                return
            link_field, _snaplen = struct.unpack_from(order + "II", body)
            if order == ">":  # LinkType then Reserved, each 16 bits
                link_field = (link_field >> 16) | ((link_field & 0xFFFF) << 16)
            link, fcs = split_link(link_field)
            unit, offset = 1e-6, 0.0
            for code, value in _options(body[8:], order):
                if code == IF_TSRESOL and value:
                    v = value[0]
                    unit = 2.0 ** -(v & 0x7F) if v & 0x80 else 10.0**-v
                elif code == IF_FCSLEN and value:
                    fcs = value[0] // 8 if value[0] >= 8 else value[0]  # bits (spec) or bytes
                elif code == IF_TSOFFSET and len(value) >= 8:
                    offset = float(struct.unpack(order + "q", value[:8])[0])
            self._interfaces.append((link, fcs, unit, offset))
            if self.link is None:
                self.link, self.fcs_bytes = link, fcs
            return
        if kind in (EPB, OPB):
            if len(body) < 20:
                yield PcapDamage("an enhanced packet block too short for its fields", self.records)
                return
            if kind == EPB:
                iface, high, low, caplen, wire = struct.unpack_from(order + "IIIII", body)
            else:
                iface, _drops, high, low, caplen, wire = struct.unpack_from(order + "HHIIII", body)
            data = body[20 : 20 + caplen]
            self.records += 1
            if iface >= len(self._interfaces):
                yield PcapDamage(
                    f"packet {self.records} names interface {iface}, which the file never "
                    "described: skipped",
                    self.records,
                )
                return
            link, fcs, unit, offset = self._interfaces[iface]
            yield Packet(
                ((high << 32) | low) * unit + offset, link, data, max(wire, len(data)), fcs
            )
            return
        if kind == SPB:
            if len(body) < 4 or not self._interfaces:
                return
            wire = struct.unpack_from(order + "I", body)[0]
            link, fcs, _unit, _offset = self._interfaces[0]
            self.records += 1
            data = body[4 : 4 + wire]
            yield Packet(0.0, link, data, max(wire, len(data)), fcs)


def _options(data: bytes, order: str) -> Iterator[tuple[int, bytes]]:
    pos = 0
    while pos + 4 <= len(data):
        code, length = struct.unpack_from(order + "HH", data, pos)
        if code == 0:
            return
        yield code, data[pos + 4 : pos + 4 + length]
        pos += 4 + ((length + 3) & ~3)
