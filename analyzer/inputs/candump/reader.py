"""candump text: ``-L`` log lines and the default screen output, parsed tolerantly and fast."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from operator import itemgetter
from typing import cast

from analyzer.inputs.base import InputItem, InputReader, by_frames, one_by_one
from analyzer.inputs.candump.line import LineError
from analyzer.inputs.candump.linewise import MAX_CACHED_IDS, CandumpLineParser
from analyzer.inputs.candump.scan import (
    DENSE,
    OTHER,
    SAMPLE,
    WHERE,
    Found,
    Place,
    WantedIdPattern,
    can_frames,
    id_texts,
    scanner,
    stamp_at,
)
from analyzer.inputs.candump.times import DECIDE_AFTER
from analyzer.inputs.textlines import (
    BLOCK_SIZE,
    MAX_LINE,
    damage_after_line,
    line_blocks,
    open_lines,
)
from analyzer.protocol.types import Event

_OTHER = itemgetter(OTHER)

__all__ = ["DECIDE_AFTER", "CandumpParser", "CandumpReader", "LineError"]


class CandumpParser(CandumpLineParser):
    """Turns candump text into CanFrames and bad_line diagnostics.

    Both ``candump -L`` (``(1436509052.249713) can0 030F0001#EB900C...``, with optional
    ``R``/``T`` suffix, ``#R`` remote frames, ``##`` CAN FD frames and error frames) and
    the default output (``can0  030F0001   [8]  EB 90 0C ...``, with the ``-t``, ``-x``,
    ``-a`` and ``-e`` variants) are understood, line by line.

    ``wanted_ids``: when given, valid frames with other IDs are checked and counted
    (``frames_skipped``) but not returned, which keeps decoding a busy bus cheap; error
    frames are always returned. ``clock`` gives the time of lines without a timestamp
    (live input); without it they get 0.0. ``scan=False`` looks at every line with the
    line parser (the reference the fast ways are tested against). ``columnar``: blocks
    dense with wanted frames are read as arrays (``columns``) and their plain frames
    handed on as FrameColumns (a file reader sets it; one line at a time has no use
    for it).
    """

    def __init__(
        self,
        source: str,
        *,
        wanted_ids: Iterable[int] | None = None,
        clock: Callable[[], float] | None = None,
        scan: bool = True,
        columnar: bool = False,
    ) -> None:
        super().__init__(source, wanted_ids=wanted_ids, clock=clock)
        self._scan = scanner(self.wanted_ids) if scan else None
        self._mixed = False  # the last block had lines for the line parser
        self._places: dict[bytes, Place] = {}  # by the scan's ``channel ID`` texts
        self.columnar = columnar and scan
        # Whether the last block was dense with wanted frames (see DENSE): the next one is
        # read as arrays. Every frame is wanted when no IDs are chosen; before the first
        # block, its start tells.
        self.dense: bool | None = True if self.wanted_ids is None else None

    # -- the block scan --------------------------------------------------------------------

    def _place(self, where: bytes) -> Place:
        """Channel name, ID value and whether extended, of a scanned ``channel ID`` text."""
        space = where.rindex(b" ")
        info = self._frame_id(where[space + 1 :])
        place = (self._channel(where[:space]), info[0], info[1])
        if len(self._places) < MAX_CACHED_IDS:
            self._places[where] = place
        return place

    def parse_lines(self, lines: list[bytes]) -> list[InputItem]:
        """Parse a list of lines (without line ends); returns frames and diagnostics."""
        return self.parse_block(b"\n".join(lines) + b"\n") if lines else []

    def parse_line(self, line: bytes) -> InputItem | None:
        """Parse one line (line end allowed); None for blank lines and skipped frames."""
        items = self.parse_lines([line.rstrip(b"\r\n")])
        return items[0] if items else None

    def parse_block(self, block: bytes) -> list[InputItem]:
        """Parse whole lines, each ending with ``\\n``; returns frames and diagnostics.

        A block of a file dense with wanted frames is read as arrays (``columnar``).
        Otherwise the scan goes over the block in one pass. When it met frame lines only (the usual
        block), the wanted frames are built a column at a time and the skipped ones are
        counted by line ends; otherwise the block is gone through match by match, and
        each line that is no well-formed frame goes to the line parser. After a block
        with such lines the next one is gone through match by match at once.
        """
        if block[-1:] != b"\n":
            block += b"\n"
        scan = self._scan
        lines, taken = self.lines, self.frames - self.frames_skipped
        if scan is None:
            out = self._parse_lines(block)
        elif self.columnar and (self.dense or (self.dense is None and self._dense_start(block))):
            out = self._parse_columns(block)
        elif self._mixed:
            out = self._parse_matches(block, scan)
        else:
            found = scan.findall(block)
            while found and not (found[-1][WHERE] or found[-1][OTHER]):
                found.pop()  # the end of the block
            if any(map(_OTHER, found)):
                out = self._parse_matches(block, scan)
            else:
                out = self._frames(found)
                self._count_scanned(block, 0, len(block), len(found))
        if self.columnar and self.lines > lines:
            taken = self.frames - self.frames_skipped - taken
            self.dense = self.wanted_ids is None or taken >= DENSE * (self.lines - lines)
        if self._held or self._times.waiting:  # frames wait for their time base (-tz / -td)
            self._held.extend(out)
            return self._release() if self.time_base is not None else []
        return out

    def _dense_start(self, block: bytes) -> bool:
        """Whether the start of ``block`` is dense with wanted frames (``DENSE``), by the
        ID texts candump writes for them."""
        sample = block[:SAMPLE]
        texts = [b" " + text.encode() + b"#" for text in id_texts(self.wanted_ids or ())]
        wanted = sum(map(sample.count, texts))
        return wanted >= DENSE * sample.count(b"\n")

    def _frames(self, found: list[Found]) -> list[InputItem]:
        """The CanFrames of the wanted frames the scan found."""
        return list(can_frames(found, self._places.get, self._place))

    def _parse_matches(self, block: bytes, scan: WantedIdPattern) -> list[InputItem]:
        """A block with lines for the line parser: each in its place, with its number."""
        out: list[InputItem] = []
        wanted: list[Found] = []  # wanted frames since the last other line
        mark = 0  # the lines from ``mark`` on are frames the scan took
        mixed = False
        for match in scan.finditer(block):
            found = cast(Found, match.groups(b""))
            if found[WHERE]:
                wanted.append(found)
                continue
            other = found[OTHER]
            if not other:
                continue  # the end of the block
            mixed = True
            out += self._frames(wanted)
            self._count_scanned(block, mark, match.start(OTHER + 1), len(wanted))
            wanted = []
            self.lines += 1
            item = self._slow_line(other[:-1][: MAX_LINE + 1], self.lines)
            if item is not None:
                out.append(item)
            mark = match.end()
        out += self._frames(wanted)
        self._count_scanned(block, mark, len(block), len(wanted))
        self._mixed = mixed
        return out

    def _parse_columns(self, block: bytes) -> list[InputItem]:
        """The block read as arrays (``columns``): runs of plain frame lines become
        FrameColumns, every other line goes to the line parser, in its place."""
        from analyzer.inputs.candump.column_runs import parse_columns

        return parse_columns(self, block)

    def _count_scanned(self, block: bytes, mark: int, pos: int, taken: int) -> None:
        """Account for the lines the scan took between ``mark`` and ``pos``, ``taken`` of
        them wanted frames (handed on) and the rest skipped frames."""
        if pos == mark:
            return
        if self.first_time is None:
            self.first_time = stamp_at(block, mark)
        lines = block.count(b"\n", mark, pos)
        self.lines += lines
        self.frames += lines
        self.frames_skipped += lines - taken
        self._after_error = False
        self.last_time = stamp_at(block, block.rfind(b"\n", mark, pos - 1) + 1 or mark)


class CandumpReader(InputReader):
    """A candump text file (``-L`` or default output), plain or gzip-compressed."""

    format_name = "candump"

    def __init__(
        self,
        path: str,
        *,
        wanted_ids: Iterable[int] | None = None,
        block_size: int = BLOCK_SIZE,
        scan: bool = True,
    ) -> None:
        super().__init__(path)
        self.block_size = block_size
        self._raw = self._open_binary()
        self._blocks, self.problems = open_lines(self._raw, block_size)
        # ``scan=False``: every line through the line parser, every frame a CanFrame (the
        # reference the fast ways are held to).
        self.parser = CandumpParser(self.source, wanted_ids=wanted_ids, scan=scan, columnar=True)

    def __iter__(self) -> Iterator[InputItem]:
        """Frames and diagnostics one by one (blocks read as columns come as CanFrames)."""
        return one_by_one(self.batches(self.block_size))

    def batches(self, size: int) -> Iterator[list[InputItem]]:
        """The items of each block of lines (in lists of at most ``size``)."""
        parser = self.parser
        raw = self._raw
        problems = self.problems
        reported = 0
        for block in line_blocks(self._blocks, self.block_size):
            items = parser.parse_block(block)
            self.position_bytes = raw.tell()
            self.first_time, self.last_time = parser.first_time, parser.last_time
            while reported < len(problems):
                items.append(self._damage(problems[reported]))
                reported += 1
            if items:
                yield from by_frames(items, size)
            else:
                yield items  # also when empty: the caller's progress moves on
        items = parser.finish()
        self.first_time, self.last_time = parser.first_time, parser.last_time
        self.time_base = parser.base_of_times()
        self.notes.extend(parser.notes)
        while reported < len(problems):
            items.append(self._damage(problems[reported]))
            reported += 1
        self.position_bytes = raw.tell()
        if items:
            yield items

    def _damage(self, problem: str) -> Event:
        """A damaged stretch of a compressed file (the lines around it are read)."""
        parser = self.parser
        return damage_after_line(self.source, parser.last_time or 0.0, parser.lines, problem)

    @property
    def stats(self) -> dict[str, int]:
        return self.parser.stats
