"""The top level of a BLF file: its header, then objects, log containers unpacked as they come.

``read_header`` checks the file header (UsageError in one line for a file that is no
BLF or whose header is damaged). ``Containers`` then reads the objects at the top level
a piece at a time and hands on their log data (each container's contents, inflated
with zlib when compressed) in pieces of at most ``PIECE`` bytes, and ``Skipped`` for
what it reads past. Memory stays bounded whatever the size fields claim: a container's
bytes are read and inflated a piece at a time, and a zlib stream that ends before the
size its container claims shows where the next object really is. Every top-level
object but a container is handed on as log data too (old files hold their objects
without containers). ``cut_at`` is set when the file ends inside an object.
"""

from __future__ import annotations

import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from typing import IO

from analyzer.errors import UsageError
from analyzer.inputs.blf.layout import (
    BASE_HEADER,
    CONTAINER_HEADER,
    FILE_HEADER,
    FILE_SIGNATURE,
    LOG_CONTAINER,
    NO_COMPRESSION,
    OBJECT_SIGNATURE,
    ZLIB_DEFLATE,
    start_time,
)
from analyzer.inputs.blf.objects import Skipped
from analyzer.inputs.blf.stream import MAX_OBJECT

PIECE = 1 << 20  # bytes read, and inflated, at a time
_SLACK = 64  # bytes after a container's zlib stream taken for its padding, not damage
_CONTAINER = BASE_HEADER.size + CONTAINER_HEADER.size  # a container's headers


@dataclass(frozen=True, slots=True)
class FileHeader:
    size: int  # the header's own size: the first object starts there
    start_time: float  # the measurement's start, seconds since 1970 (0.0: none)
    file_size: int = 0  # the whole file's size as its writer left it (0: not written)


def read_header(handle: IO[bytes], path: str, file_size: int | None) -> FileHeader:
    """The file header; UsageError for anything that is no BLF header."""
    head = handle.read(FILE_HEADER.size)
    if len(head) < FILE_HEADER.size or head[:4] != FILE_SIGNATURE:
        raise UsageError(f"cannot read {path} as blf: it does not start with a BLF header")
    fields = FILE_HEADER.unpack(head)
    size = fields[1]
    if size < FILE_HEADER.size or (file_size is not None and size > file_size):
        where = f" in a file of {file_size:,} bytes" if file_size is not None else ""
        raise UsageError(
            f"cannot read {path} as blf: its header claims to be {size:,} bytes long{where} "
            "(a damaged or not a BLF file)"
        )
    _skip(handle, size - FILE_HEADER.size)
    return FileHeader(size, start_time(fields[14:22]), fields[10])


class Containers:
    """The log data of the objects after the header (see the module docstring)."""

    def __init__(self, handle: IO[bytes], offset: int) -> None:
        self._handle = handle
        self._back = b""  # bytes read ahead and given back
        self.offset = offset  # where the next byte comes from in the file
        self.cut_at: int | None = None

    def pieces(self) -> Iterator[bytes | Skipped]:
        while True:
            at = self.offset
            head = self._read(BASE_HEADER.size)
            if len(head) < BASE_HEADER.size:
                if any(head):
                    self.cut_at = self.offset
                return
            if head[:4] != OBJECT_SIGNATURE:
                yield from self._resync(head, at)
                continue
            _, _, _, size, kind = BASE_HEADER.unpack(head)
            if kind == LOG_CONTAINER and size >= _CONTAINER:
                yield from self._container(at, size)
            elif kind != LOG_CONTAINER and BASE_HEADER.size <= size <= MAX_OBJECT:
                rest = self._read(size - BASE_HEADER.size)
                yield head + rest
                if len(rest) < size - BASE_HEADER.size:
                    return  # the stream says where its object was cut
            else:
                yield Skipped(
                    "objects", f"an object at byte {at:,} claiming {size:,} bytes skipped"
                )
                yield from self._resync(head[4:], at + 4)
                continue
            self._read(size % 4)  # padding

    def _container(self, at: int, size: int) -> Iterator[bytes | Skipped]:
        head = self._read(CONTAINER_HEADER.size)
        if len(head) < CONTAINER_HEADER.size:
            self.cut_at = self.offset
            return
        method, _ = CONTAINER_HEADER.unpack(head)
        left = size - _CONTAINER
        if method == ZLIB_DEFLATE:
            yield from self._inflate(at, left)
        elif method == NO_COMPRESSION:
            while left > 0:
                piece = self._read(min(left, PIECE))
                if not piece:
                    self.cut_at = self.offset
                    return
                left -= len(piece)
                yield piece
        else:
            yield Skipped(
                "log containers",
                f"a log container at byte {at:,} skipped: compressed with method {method}, "
                "which Vector does not document",
            )
            self._drop(left)

    def _inflate(self, at: int, left: int) -> Iterator[bytes | Skipped]:
        """A zlib container's data, a piece at a time; its stream's end is believed over
        a size that claims much more."""
        inflate = zlib.decompressobj()
        while left > 0 and not inflate.eof:
            piece = self._read(min(left, PIECE))
            if not piece:
                self.cut_at = self.offset
                yield inflate.flush()  # what a stream cut short still gives
                return
            left -= len(piece)
            try:
                while piece and not inflate.eof:
                    yield inflate.decompress(piece, PIECE)
                    piece = inflate.unconsumed_tail
            except zlib.error as exc:
                yield Skipped(
                    "log containers", f"the rest of the log container at byte {at:,} skipped: {exc}"
                )
                self._drop(left)
                return
            if inflate.eof:
                piece = inflate.unused_data
                if left + len(piece) > _SLACK:  # its size claims more than its stream
                    self._give_back(piece)
                    yield Skipped(
                        "log containers",
                        f"the log container at byte {at:,} claims {left + len(piece):,} "
                        "bytes more than its compressed data holds: read on after its data",
                    )
                    return
        yield inflate.flush()  # what a stream cut short still gives
        self._drop(left)

    def _resync(self, head: bytes, at: int) -> Iterator[Skipped]:
        """No object where one should start: read on to the next signature."""
        skipped, tail, zeros = 0, head, not any(head)
        while True:
            found = tail.find(OBJECT_SIGNATURE)
            if found >= 0:
                self._give_back(tail[found:])
                skipped += found
                zeros = zeros and not any(tail[:found])
                break
            keep = len(OBJECT_SIGNATURE) - 1
            skipped += max(0, len(tail) - keep)
            zeros = zeros and not any(tail[:-keep])
            more = self._read(PIECE)
            if not more:
                skipped += min(len(tail), keep)
                zeros = zeros and not any(tail)
                break
            tail = tail[-keep:] + more
        if skipped and not zeros:
            yield Skipped("bytes", f"{skipped:,} bytes at byte {at:,} skipped: no object there")

    def _read(self, count: int) -> bytes:
        """Up to ``count`` bytes (fewer only at the end of the file)."""
        out = self._back[:count]
        self._back = self._back[count:]
        while len(out) < count:
            piece = self._handle.read(min(count - len(out), PIECE))
            if not piece:
                break
            out += piece
        self.offset += len(out)
        return out

    def _give_back(self, data: bytes) -> None:
        self._back = data + self._back
        self.offset -= len(data)

    def _drop(self, count: int) -> None:
        while count > 0:
            piece = self._read(min(count, PIECE))
            if not piece:
                return
            count -= len(piece)


def _skip(handle: IO[bytes], count: int) -> None:
    while count > 0:
        piece = handle.read(min(count, PIECE))
        if not piece:
            return
        count -= len(piece)
