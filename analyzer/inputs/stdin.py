"""Standard input: candump text read line by line as it arrives (``candump -L can0 | ...``)."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable, Iterator
from typing import IO

from analyzer import wall_clock
from analyzer.inputs.base import InputItem, InputReader
from analyzer.inputs.candump.reader import CandumpParser
from analyzer.inputs.textlines import MAX_LINE
from analyzer.protocol.types import StreamChunk

STREAM_READ_SIZE = 4096


class StdinCandumpReader(InputReader):
    """candump text from a pipe; every line is handed on as soon as it is complete.

    Lines without a timestamp (plain ``candump can0``) get the time they were read.
    """

    format_name = "candump"

    def __init__(
        self, stream: IO[bytes] | None = None, *, wanted_ids: Iterable[int] | None = None
    ) -> None:
        super().__init__("-")
        self._stream = stream if stream is not None else sys.stdin.buffer
        self.parser = CandumpParser(self.source, wanted_ids=wanted_ids, clock=time.time)

    def __iter__(self) -> Iterator[InputItem]:
        parser = self.parser
        readline = self._stream.readline
        while True:
            line = readline(MAX_LINE + 1)
            if not line:
                break
            self.position_bytes += len(line)
            if len(line) > MAX_LINE and not line.endswith(b"\n"):
                # Too long to be a frame: keep its start for the diagnostic, skip the rest
                # up to the line end without holding it (``split_blocks`` does the same).
                while True:
                    rest = readline(MAX_LINE)
                    self.position_bytes += len(rest)
                    if not rest or rest.endswith(b"\n"):
                        break
            items = parser.parse_lines([line.rstrip(b"\r\n")])
            self.first_time, self.last_time = parser.first_time, parser.last_time
            yield from items
        yield from parser.finish()
        self.first_time, self.last_time = parser.first_time, parser.last_time
        self.time_base = parser.base_of_times()
        self.notes.extend(parser.notes)

    @property
    def stats(self) -> dict[str, int]:
        return self.parser.stats


class StdinStreamReader(InputReader):
    """Raw TCP / UART bytes from a pipe, handed on as they arrive, stamped with the clock."""

    format_name = "stream"

    def __init__(self, stream: IO[bytes] | None = None) -> None:
        super().__init__("-")
        self._stream = stream if stream is not None else sys.stdin.buffer
        self.chunks = 0

    def __iter__(self) -> Iterator[InputItem]:
        read = getattr(self._stream, "read1", self._stream.read)
        while True:
            data = read(STREAM_READ_SIZE)
            if not data:
                break
            self.position_bytes += len(data)
            self.chunks += 1
            now = wall_clock.now()
            if self.first_time is None:
                self.first_time = now
            self.last_time = now
            yield StreamChunk(now, bytes(data), self.source)

    @property
    def stats(self) -> dict[str, int]:
        return {"bytes": self.position_bytes, "chunks": self.chunks}
