"""MF4 files checked before asammdf reads them: a data group whose records are not
counted, or a chain of groups that comes back on itself, makes asammdf loop for ever; a
channel placed outside its record makes it read outside its buffer and crash the
process; a record size of gigabytes makes it allocate them (ASAM MDF 4.x block layout)."""

from __future__ import annotations

import struct
from typing import IO, NamedTuple

_BLOCK = struct.Struct("<4s4xQQ")  # id "##XX", reserved, length, link count
_HD_AT = 64  # the header block follows the 64-byte identification block
_MAX_CHAIN = 100_000  # a longer chain of blocks is a loop in a damaged file
_DATA_BLOCKS = (b"##DT", b"##DZ", b"##DL", b"##HL")
# A channel group's data: cg_record_id, cg_cycle_count, cg_flags, cg_path_separator,
# reserved, cg_data_bytes (the record's size), cg_inval_bytes; a VLSD group (flag bit 0)
# has no records.
_GROUP_DATA = struct.Struct("<QQHH4xII")
_VLSD_GROUP = 1
# asammdf allocates a whole record at once whatever the data holds. A CAN bus-logging
# record (a frame's time, ID, flags, length, and its data bytes or where they are) takes
# well under 200 bytes; a record size beyond this is a damaged field.
_MOST_RECORD = 1 << 20
# A channel's data: cn_type, cn_sync_type, cn_data_type, cn_bit_offset, cn_byte_offset,
# cn_bit_count; virtual channels (types 3, 6) take no bytes of the record.
_CHANNEL_DATA = struct.Struct("<BBBBII")
_VIRTUAL = (3, 6)
# asammdf reads a channel block of these lengths at a fixed layout of this many links,
# whatever its link count says: so does this check.
_CHANNEL_LINKS = {160: 8, 168: 9}


class _Block(NamedTuple):
    kind: bytes
    length: int
    links: list[int]
    data_at: int  # where the block's data part starts


class _Blocks:
    """Block headers of an MF4 file, each read where a link points."""

    def __init__(self, handle: IO[bytes], size: int) -> None:
        self.handle = handle
        self.size = size

    def at(self, offset: int, kind: bytes) -> _Block | None:
        """The block of this kind at ``offset`` (None when there is none)."""
        if offset <= 0 or offset + _BLOCK.size > self.size:
            return None
        self.handle.seek(offset)
        head = self.handle.read(_BLOCK.size)
        if len(head) < _BLOCK.size:
            return None
        found, length, count = _BLOCK.unpack(head)
        if found == b"##CN":
            count = _CHANNEL_LINKS.get(length, count)
        end = offset + _BLOCK.size + 8 * count
        if (kind and found != kind) or count > 1024 or end > self.size:
            return None
        links = list(struct.unpack(f"<{count}Q", self.handle.read(8 * count)))
        return _Block(found, length, links, end)

    def cycles(self, first: int) -> int:
        """The records the chain of channel groups from ``first`` counts."""
        total, offset = 0, first
        seen: set[int] = set()
        while offset and offset not in seen and len(seen) < _MAX_CHAIN:
            seen.add(offset)
            group = self.at(offset, b"##CG")
            if group is None or not group.links:
                return total
            self.handle.seek(group.data_at + 8)  # after cg_record_id: cg_cycle_count
            total += int.from_bytes(self.handle.read(8), "little")
            offset = group.links[0]
        return total

    def data(self, block: _Block, layout: struct.Struct) -> tuple[int, ...] | None:
        if block.data_at + layout.size > self.size:
            return None
        self.handle.seek(block.data_at)
        return layout.unpack(self.handle.read(layout.size))

    def group_problem(self, first_group: int) -> str | None:
        """A record of the chain of channel groups from ``first_group`` too large to be
        one, or a channel outside its group's record (its sub-channels included); None
        when there is neither."""
        offset, groups = first_group, 0
        while offset and groups < _MAX_CHAIN:
            groups += 1
            group = self.at(offset, b"##CG")
            sizes = self.data(group, _GROUP_DATA) if group is not None else None
            if group is None or sizes is None or len(group.links) < 2:
                return None
            if not sizes[2] & _VLSD_GROUP:
                record = sizes[4] + sizes[5]
                if record > _MOST_RECORD:
                    return (
                        f"its channel group at byte {offset:,} has records of {record:,} "
                        "bytes, more than a CAN bus-logging record holds (a damaged MF4 "
                        "file, for which asammdf would allocate them)"
                    )
                found = self._outside(group.links[1], sizes[4])
                if found:
                    return found
            offset = group.links[0]
        return None

    def _outside(self, first: int, record: int) -> str | None:
        pending: list[int] = [first]
        seen: set[int] = set()
        while pending and len(seen) < _MAX_CHAIN:
            offset = pending.pop()
            if not offset or offset in seen:
                continue
            seen.add(offset)
            channel = self.at(offset, b"##CN")
            fields = self.data(channel, _CHANNEL_DATA) if channel is not None else None
            if channel is None or fields is None:
                continue
            pending += channel.links[:2]  # the next channel, the sub-channels
            kind, _, _, bit_offset, byte_offset, bits = fields
            end = byte_offset + (bit_offset + bits + 7) // 8
            if kind not in _VIRTUAL and end > record:
                return (
                    f"its channel at byte {offset:,} ends at byte {end:,} of a record of "
                    f"{record:,} bytes (a damaged MF4 file, which asammdf would read outside "
                    "its memory)"
                )
        return None

    def link(self, offset: int) -> int | None:
        """The 8-byte link at ``offset`` (None past the end of the file)."""
        if offset < 0 or offset + 8 > self.size:
            return None
        self.handle.seek(offset)
        return int.from_bytes(self.handle.read(8), "little")

    def chain_loop(self) -> str | None:
        """Where a chain of data groups, or of a data group's channel groups, comes back on
        itself, followed as asammdf counts the groups before it reads a file: by the raw
        links (the next at +24, a data group's first channel group at +32), whatever
        block is there. None when every chain ends (or leaves the file: asammdf says so)."""
        groups: set[int] = set()
        group = self.link(_HD_AT + 24)  # the header's first link: the first data group
        while group and len(groups) < _MAX_CHAIN:
            if group in groups:
                return _looping("data groups", group)
            groups.add(group)
            channel_groups: set[int] = set()
            channel_group = self.link(group + 32)
            while channel_group and len(channel_groups) < _MAX_CHAIN:
                if channel_group in channel_groups:
                    return _looping("channel groups", channel_group)
                channel_groups.add(channel_group)
                channel_group = self.link(channel_group + 24)
            group = self.link(group + 24)
        return None

    def holds_data(self, offset: int) -> bool:
        block = self.at(offset, b"")
        if block is None or block.kind not in _DATA_BLOCKS:
            return False
        return block.kind != b"##DT" or block.length > _BLOCK.size


def _looping(what: str, offset: int) -> str:
    return (
        f"its chain of {what} comes back to byte {offset:,} (a damaged MF4 file, which "
        "asammdf would follow for ever)"
    )


def mf4_problem(handle: IO[bytes], size: int) -> str | None:
    """Why asammdf cannot be given this file (None: nothing found wrong). Reads only
    the headers of the data groups, their channel groups and data blocks."""
    blocks = _Blocks(handle, size)
    try:
        loop = blocks.chain_loop()  # followed by asammdf whatever the header block holds
        if loop:
            return loop
        header = blocks.at(_HD_AT, b"##HD")
        if header is None or not header.links:
            return None  # not laid out as expected: asammdf says what is wrong
        seen: set[int] = set()
        offset = header.links[0]
        while offset and offset not in seen and len(seen) < _MAX_CHAIN:
            seen.add(offset)
            group = blocks.at(offset, b"##DG")
            if group is None or len(group.links) < 3:
                return None
            if not blocks.cycles(group.links[1]) and blocks.holds_data(group.links[2]):
                return (
                    f"its data group at byte {offset:,} holds data but counts no record "
                    "(a damaged or unfinished MF4 file, which asammdf cannot read)"
                )
            outside = blocks.group_problem(group.links[1])
            if outside:
                return outside
            offset = group.links[0]
    except (OSError, struct.error):
        return None
    finally:
        handle.seek(0)
    return None
