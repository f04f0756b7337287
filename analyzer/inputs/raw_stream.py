"""Raw byte dumps of a TCP or UART stream (``.bin``): the bytes, in order, without timestamps."""

from __future__ import annotations

from collections.abc import Iterator

from analyzer.inputs.base import InputItem, InputReader
from analyzer.inputs.content import describe
from analyzer.protocol.types import StreamChunk

CHUNK_SIZE = 1 << 16


class RawStreamReader(InputReader):
    """A file of stream bytes; handed on in chunks, all at time 0.0 (a dump has no clock).

    ``direction`` (``gs_to_idu`` / ``idu_to_gs``) may be given when it is known which
    side of the link was dumped.
    """

    format_name = "stream"

    def __init__(self, path: str, *, direction: str = "", chunk_size: int = CHUNK_SIZE) -> None:
        super().__init__(path)
        self._handle = self._open_binary()
        self.direction = direction
        self.chunk_size = chunk_size
        self.chunks = 0
        head = self._handle.read(4096)
        self._handle.seek(0)
        # What the bytes look like when they are something else (a DataFlash log, a capture).
        self.looks_like = describe(head)
        if self.looks_like is not None and self.looks_like[1] is not None:
            words, fmt = self.looks_like
            self.notes.append(
                f"{self.source} looks like {words}, not a raw TCP/UART stream: "
                f"read it with --format {fmt}"
            )

    def __iter__(self) -> Iterator[InputItem]:
        read = self._handle.read
        while True:
            data = read(self.chunk_size)
            if not data:
                break
            self.position_bytes += len(data)
            self.chunks += 1
            yield StreamChunk(0.0, data, self.source, self.direction)

    @property
    def stats(self) -> dict[str, int]:
        return {"bytes": self.position_bytes, "chunks": self.chunks}
