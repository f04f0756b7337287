"""Text capture files as lines: gzip read like zcat (damage kept local), long lines cut, counted."""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator
from typing import IO, Any

from analyzer.protocol.types import BAD_LINE, Event, diagnostic

BLOCK_SIZE = 1 << 20  # bytes read at a time
MAX_LINE = 1 << 16  # a longer line is cut to this length (plus one byte: see ``is_overlong``)
GZIP_MAGIC = b"\x1f\x8b"
_MEMBER_START = b"\x1f\x8b\x08"  # gzip magic and the deflate method
_OUT_LIMIT = 1 << 20  # decompressed bytes produced per step (bounds a decompression bomb)
_READ_SIZE = 1 << 16  # compressed bytes fed per step
_MAX_HEADER = 1 << 16  # bytes of a member header looked at (file name, comment, extra)
_TRAILER = struct.Struct("<II")  # CRC-32 and size of the member's text


def is_overlong(line: bytes) -> bool:
    """Whether ``split_blocks`` cut this line because it was longer than MAX_LINE."""
    return len(line) > MAX_LINE


class TolerantGunzip:
    """Decompresses a gzip file the way ``zcat`` does, and goes further after damage.

    Every byte that decompresses is handed on, also the part of a member before a
    corruption or a cut (``gzip.GzipFile`` loses the whole block it was reading). After
    a corrupt stretch, reading resumes at the next gzip member header, if there is one.
    ``problems`` says, in words, what was wrong and where (compressed byte offsets).
    """

    def __init__(self, raw: IO[bytes], read_size: int = _READ_SIZE) -> None:
        self._raw = raw
        self._read_size = read_size
        self.problems: list[str] = []
        self.members = 0
        self._data = b""
        self._pos = 0  # compressed offset of _data[0]
        self._skipped: list[int] = []  # a run of skipped bytes: [offset, size]

    def read_blocks(self) -> Iterator[bytes]:
        """The decompressed bytes, in pieces of at most about 1 MiB."""
        while self._fill(1):
            start = _find_member(self._data)
            if start < 0:  # between members or after the last: look further
                keep = min(2, len(self._data))  # a header may straddle two reads
                self._garbage(self._data[: len(self._data) - keep])
                self._drop(len(self._data) - keep)
                self._fill(keep + 1)
                if len(self._data) <= keep:  # the end of the file
                    self._garbage(self._data)
                    break
                continue
            self._garbage(self._data[:start])
            self._drop(start)
            self._flush_garbage()
            yield from self._member()
        self._flush_garbage()

    def _member(self) -> Iterator[bytes]:
        """One member from ``_data[0]`` on: its text, then its trailer checked."""
        begin = self._pos
        self._fill(_MAX_HEADER)
        header = _header_length(self._data)
        if header is None:
            self.problems.append(f"damaged gzip header at compressed byte {begin:,}: skipped")
            self._drop(1)
            return
        self.members += 1
        self._drop(header)
        decomp = zlib.decompressobj(-zlib.MAX_WBITS)
        crc = size = 0
        while not decomp.eof:
            if not self._fill(1):
                self.problems.append(
                    f"the gzip file is cut off after {self._pos:,} compressed bytes (as a "
                    "logger that lost power leaves it): everything before the cut was read"
                )
                return
            data = self._data
            saved = decomp.copy()
            try:
                out = decomp.decompress(data, _OUT_LIMIT)
                pieces = [out]
                while decomp.unconsumed_tail and not decomp.eof:
                    pieces.append(decomp.decompress(decomp.unconsumed_tail, _OUT_LIMIT))
            except zlib.error as exc:
                out = b"".join(_salvage(saved, data))  # what zcat writes before it stops
                if out:
                    crc, size = zlib.crc32(out, crc), size + len(out)
                    yield out
                self.problems.append(
                    f"gzip data damaged after {size:,} decompressed bytes of the member at "
                    f"compressed byte {begin:,} ({exc}): the text before the damage is kept, "
                    "reading goes on at the next gzip member if there is one"
                )
                self._drop(1)
                return
            for out in pieces:
                if out:
                    crc, size = zlib.crc32(out, crc), size + len(out)
                    yield out
            self._drop(len(data) - len(decomp.unused_data))
        self._fill(8)
        trailer = self._data[:8]
        if len(trailer) < 8:
            self.problems.append(
                f"the gzip file is cut off in the trailer of the member at compressed byte "
                f"{begin:,}: its text was read but could not be checked"
            )
        elif _TRAILER.unpack(trailer) != (crc, size & 0xFFFFFFFF):
            self.problems.append(
                f"the gzip member at compressed byte {begin:,} fails its CRC check: some of "
                "its text may be wrong (damaged lines are reported as such)"
            )
        self._drop(len(trailer))

    def _fill(self, wanted: int) -> bool:
        """Read until ``_data`` holds ``wanted`` bytes (or the file ends); whether any."""
        while len(self._data) < wanted:
            more = self._raw.read(self._read_size)
            if not more:
                break
            self._data += more
        return bool(self._data)

    def _drop(self, count: int) -> None:
        self._data = self._data[count:]
        self._pos += count

    def _garbage(self, skipped: bytes) -> None:
        """Bytes between members that are no gzip data (zero padding is no damage)."""
        if not skipped.strip(b"\0"):
            return
        run = self._skipped
        if run and run[0] + run[1] == self._pos:
            run[1] += len(skipped)
        else:
            self._flush_garbage()
            self._skipped = [self._pos, len(skipped)]

    def _flush_garbage(self) -> None:
        if self._skipped:
            start, size = self._skipped
            self.problems.append(
                f"{size:,} byte(s) that are no gzip data at compressed byte {start:,} were skipped"
            )
            self._skipped = []


def _salvage(decomp: Any, data: bytes) -> Iterator[bytes]:
    """Feed ``data`` a byte at a time to a copy of the decompressor until it fails."""
    for i in range(len(data)):
        try:
            out = decomp.decompress(data[i : i + 1])
        except zlib.error:
            return
        if out:
            yield out
        if decomp.eof:
            return


def _header_length(data: bytes) -> int | None:
    """Length of the gzip member header at ``data[0]``; None when it is not one."""
    if len(data) < 10 or data[:3] != _MEMBER_START or data[3] >= 0x20:
        return None
    flags, pos = data[3], 10
    if flags & 0x04:  # FEXTRA
        if len(data) < pos + 2:
            return None
        pos += 2 + int.from_bytes(data[pos : pos + 2], "little")
    for flag in (0x08, 0x10):  # FNAME, FCOMMENT: zero-terminated
        if flags & flag:
            end = data.find(b"\0", pos)
            if end < 0:
                return None
            pos = end + 1
    if flags & 0x02:  # FHCRC
        pos += 2
    return pos if pos <= len(data) else None


def _find_member(data: bytes) -> int:
    """Offset of a plausible gzip member header in ``data`` (-1 when there is none)."""
    start = data.find(_MEMBER_START)
    while start >= 0:
        flags = data[start + 3 : start + 4]
        if not flags or flags[0] < 0x20:  # reserved flag bits are zero in a real header
            return start
        start = data.find(_MEMBER_START, start + 1)
    return -1


def line_blocks(
    blocks: Iterator[bytes] | IO[bytes], block_size: int = BLOCK_SIZE
) -> Iterator[bytes]:
    """Whole lines of a byte source, many at a time, each block ending with ``\\n``.

    ``blocks`` is an iterator of byte blocks or a binary file (read ``block_size`` at a
    time). CRLF line ends become LF. One line is one line whatever its length, so line
    numbers stay right: a line with no line end within MAX_LINE bytes is cut to
    MAX_LINE + 1 bytes (``is_overlong``) and the rest of it up to the line end is skipped,
    so memory stays bounded. Lines inside a block may still be longer than MAX_LINE
    (up to a block): whoever looks at one line on its own cuts it. The last line of the
    source gets a line end if it has none.
    """
    if not isinstance(blocks, Iterator):
        handle = blocks
        blocks = iter(lambda: handle.read(block_size), b"")
    tail = b""
    skipping = False  # inside an overlong line whose start has been handed on
    for block in blocks:
        if skipping:
            end = block.find(b"\n")
            if end < 0:
                continue
            block = block[end + 1 :]
            skipping = False
        if tail:
            block = tail + block
        if b"\r" in block:  # CRLF line ends
            block = block.replace(b"\r\n", b"\n")
        cut = block.rfind(b"\n") + 1
        tail = block[cut:]
        body = block[:cut]
        if len(tail) > MAX_LINE:  # no line end in sight: hand on its start, skip the rest
            body += tail[: MAX_LINE + 1] + b"\n"
            tail = b""
            skipping = True
        if body:
            yield body
    if tail:
        yield tail.rstrip(b"\r") + b"\n"


def split_blocks(
    blocks: Iterator[bytes] | IO[bytes], block_size: int = BLOCK_SIZE
) -> Iterator[list[bytes]]:
    """Lines (line ends removed) of a byte source, a list at a time (see ``line_blocks``).

    Every line handed on is at most MAX_LINE + 1 bytes long (``is_overlong``).
    """
    for block in line_blocks(blocks, block_size):
        lines = block.split(b"\n")
        lines.pop()  # the empty text after the block's last line end
        if max(map(len, lines)) > MAX_LINE:  # rare: look line by line only then
            for i, line in enumerate(lines):
                if len(line) > MAX_LINE:
                    lines[i] = line[: MAX_LINE + 1]
        yield lines


def open_lines(raw: IO[bytes], block_size: int = BLOCK_SIZE) -> tuple[Iterator[bytes], list[str]]:
    """The byte blocks of a plain or gzip-compressed text file, and its problem list.

    The problem list fills while the blocks are read (gzip damage, see TolerantGunzip).
    """
    head = raw.read(2)
    raw.seek(0)
    if head == GZIP_MAGIC:
        gunzip = TolerantGunzip(raw)
        return gunzip.read_blocks(), gunzip.problems
    return iter(lambda: raw.read(block_size), b""), []


def damage_after_line(source: str, time: float, line: int, problem: str) -> Event:
    """A problem of ``open_lines`` (a damaged stretch of a compressed file) as the
    diagnostic of a text reader: said after ``line``, the last line read (the lines
    around the damage are read)."""
    return diagnostic(time, source, BAD_LINE, f"after line {line}: {problem}", line=line)
