"""candump text: ``-L`` log lines and the default screen output, parsed tolerantly and fast."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from operator import itemgetter
from typing import cast

from analyzer.inputs.base import InputItem, InputReader, by_frames
from analyzer.inputs.candump_line import (
    RELATIVE_LIMIT,
    IdInfo,
    LineError,
    id_info,
    parse_log_line,
    parse_screen_line,
)
from analyzer.inputs.candump_scan import (
    OTHER,
    WHERE,
    Found,
    Place,
    Scan,
    can_frames,
    frame_run,
    scanner,
    stamp_at,
)
from analyzer.inputs.candump_times import DECIDE_AFTER, ScreenTimes
from analyzer.inputs.python_can_text import ABSOLUTE, RELATIVE_TO_START
from analyzer.inputs.textlines import BLOCK_SIZE, MAX_LINE, line_blocks, open_lines
from analyzer.protocol.types import BAD_LINE, Event, diagnostic

RAW_LIMIT = 200  # bytes of a bad line kept in its diagnostic
FOREIGN_HEAD = 20  # first bad lines looked at to tell what a file that is no candump is
FOREIGN_BAD = 10  # bad lines (with under a tenth as many frames) that make it no candump
# ID texts and channel names kept in the caches; beyond that (a log of random IDs) a text
# is looked at anew each time, and memory stays flat.
MAX_CACHED_IDS = 20_000
MAX_CACHED_CHANNELS = 10_000
# Frames in one FrameRun: a batch's frames and events then stay few enough to be in the
# processor's caches while the decoder and the counters go over them.
RUN_FRAMES = 2048

_OTHER = itemgetter(OTHER)

__all__ = ["DECIDE_AFTER", "CandumpParser", "CandumpReader", "LineError"]


class CandumpParser:
    """Turns candump text into CanFrames and bad_line diagnostics.

    Both ``candump -L`` (``(1436509052.249713) can0 030F0001#EB900C...``, with optional
    ``R``/``T`` suffix, ``#R`` remote frames, ``##`` CAN FD frames and error frames) and
    the default output (``can0  030F0001   [8]  EB 90 0C ...``, with the ``-t``, ``-x``,
    ``-a`` and ``-e`` variants) are understood, line by line.

    ``wanted_ids``: when given, valid frames with other IDs are checked and counted
    (``frames_skipped``) but not returned, which keeps decoding a busy bus cheap; error
    frames are always returned. ``clock`` gives the time of lines without a timestamp
    (live input); without it they get 0.0. ``scan=False`` looks at every line with the
    line parser (the reference the fast scan is tested against).
    """

    def __init__(
        self,
        source: str,
        *,
        wanted_ids: Iterable[int] | None = None,
        clock: Callable[[], float] | None = None,
        scan: bool = True,
    ) -> None:
        self.source = source
        self.wanted_ids = None if wanted_ids is None else frozenset(wanted_ids)
        self.clock = clock
        self._scan = scanner(self.wanted_ids) if scan else None
        self._mixed = False  # the last block had lines for the line parser
        self.frame_runs = False  # hand on the scanned frames as FrameRuns
        self.lines = 0
        self.frames = 0  # valid frames, skipped ones included
        self.frames_skipped = 0
        self.bad_lines = 0
        self.blank_lines = 0
        self.note_lines = 0  # error-frame explanations of ``candump -e``
        self.first_time: float | None = None
        self.last_time: float | None = None
        self._ids: dict[bytes, IdInfo | None] = {}
        self._channels: dict[bytes, str] = {}
        self._places: dict[bytes, Place] = {}  # by the scan's ``channel ID`` texts
        self._after_error = False
        self._times = ScreenTimes()
        self._held: list[InputItem] = []
        # A file that is no candump at all (BusMaster and others also write .log).
        self._head: list[bytes] = []  # the first bad lines, to tell what the file is
        self.not_candump = False
        self.bad_lines_not_shown = 0
        self.notes: list[str] = []

    @property
    def stats(self) -> dict[str, int]:
        return {
            "lines": self.lines,
            "frames": self.frames,
            "other_frames": self.frames_skipped,
            "bad_lines": self.bad_lines,
            "blank_lines": self.blank_lines,
            "note_lines": self.note_lines,
        }

    # -- ID and channel caches -------------------------------------------------------------

    def _frame_id(self, text: bytes) -> IdInfo:
        ids = self._ids
        info = ids[text] if text in ids else id_info(text, self.wanted_ids)
        if len(ids) < MAX_CACHED_IDS:  # a file of random IDs must not grow the cache
            ids[text] = info
        if info is None:
            raise LineError(f"bad CAN ID {text.decode('ascii', 'replace')!r}")
        return info

    def _place(self, where: bytes) -> Place:
        """Channel name, ID value and whether extended, of a scanned ``channel ID`` text."""
        space = where.rindex(b" ")
        info = self._frame_id(where[space + 1 :])
        place = (self._channel(where[:space]), info[0], info[1])
        if len(self._places) < MAX_CACHED_IDS:
            self._places[where] = place
        return place

    def _channel(self, text: bytes) -> str:
        name = self._channels.get(text)
        if name is None:
            name = text.decode("ascii", "replace")
            if len(self._channels) < MAX_CACHED_CHANNELS:
                self._channels[text] = name
        return name

    # -- lines -----------------------------------------------------------------------------

    def parse_lines(self, lines: list[bytes]) -> list[InputItem]:
        """Parse a list of lines (without line ends); returns frames and diagnostics."""
        return self.parse_block(b"\n".join(lines) + b"\n") if lines else []

    def parse_line(self, line: bytes) -> InputItem | None:
        """Parse one line (line end allowed); None for blank lines and skipped frames."""
        items = self.parse_lines([line.rstrip(b"\r\n")])
        return items[0] if items else None

    def parse_block(self, block: bytes) -> list[InputItem]:
        """Parse whole lines, each ending with ``\\n``; returns frames and diagnostics.

        The scan goes over the block in one pass. When it met frame lines only (the usual
        block), the wanted frames are built a column at a time and the skipped ones are
        counted by line ends; otherwise the block is gone through match by match, and
        each line that is no well-formed frame goes to the line parser. After a block
        with such lines the next one is gone through match by match at once.
        """
        if block[-1:] != b"\n":
            block += b"\n"
        scan = self._scan
        if scan is None:
            out = self._parse_lines(block)
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
        if self._held or self._times.waiting:  # frames wait for their time base (-tz / -td)
            self._held.extend(out)
            return self._release() if self.time_base is not None else []
        return out

    def _frames(self, found: list[Found]) -> list[InputItem]:
        """The CanFrames of the wanted frames the scan found (one FrameRun of them all
        when ``frame_runs`` is set)."""
        if self.frame_runs:
            return [
                frame_run(found[start : start + RUN_FRAMES], self._places.get, self._place)
                for start in range(0, len(found), RUN_FRAMES)
            ]
        return list(can_frames(found, self._places.get, self._place))

    def _parse_matches(self, block: bytes, scan: Scan) -> list[InputItem]:
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

    def _parse_lines(self, block: bytes) -> list[InputItem]:
        """Every line of the block by the line parser (no scan)."""
        out: list[InputItem] = []
        pos, size = 0, len(block)
        while pos < size:
            eol = block.index(b"\n", pos)
            self.lines += 1
            item = self._slow_line(block[pos : min(eol, pos + MAX_LINE + 1)], self.lines)
            if item is not None:
                out.append(item)
            pos = eol + 1
        return out

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

    def _bad(self, line: bytes, lineno: int, why: str) -> Event | None:
        self.bad_lines += 1
        self._after_error = False
        if len(self._head) < FOREIGN_HEAD:
            self._head.append(line[:RAW_LIMIT])
            if self.bad_lines >= FOREIGN_BAD and self.frames * 10 < self.bad_lines:
                self._foreign_note()
        if self.not_candump:
            self.bad_lines_not_shown += 1
            return None
        shown = line[:RAW_LIMIT]
        text = shown.decode("ascii", "replace").strip()
        if len(text) > 60:
            text = text[:57] + "..."
        return diagnostic(
            self.last_time if self.last_time is not None else 0.0,
            self.source,
            BAD_LINE,
            f"line {lineno}: {why}: {text!r}",
            shown,
            line=lineno,
        )

    def _foreign_note(self) -> None:
        """Nearly nothing parses: say once what the file looks like; stop listing lines."""
        if self.not_candump:
            return
        self.not_candump = True
        from analyzer.inputs import FORMATS, sniff_format  # the dispatcher imports us

        head = b"\n".join(self._head)
        if b"***BUSMASTER" in head.upper():
            what = (
                "it looks like a BusMaster log, which gimbal-analyzer does not read: export "
                "it to ASC or BLF with BusMaster's format converter and decode that"
            )
        else:
            fmt = sniff_format(head)
            what = (
                f"it looks like {FORMATS[fmt]}: try --format {fmt}"
                if fmt not in (None, "candump")
                else f"give its format with --format ({', '.join(FORMATS)})"
            )
        self.notes.append(
            f"{self.source} is not candump output: none of its first {len(self._head)} "
            f"lines is a CAN frame; {what}. Further bad lines are counted, not listed."
        )

    def _slow_line(self, line: bytes, lineno: int) -> InputItem | None:
        """Any line, looked at on its own: a frame, a bad line or nothing (blank, note)."""
        stripped = line.strip()
        if not stripped:
            self.blank_lines += 1
            return None
        if line[:1] == b"\t" and self._after_error:
            self.note_lines += 1  # ``candump -e`` explains an error frame on extra lines
            return None
        if len(line) > MAX_LINE:
            return self._bad(line, lineno, f"line longer than {MAX_LINE:,} bytes")
        if stripped[:1] == b"#":
            return self._bad(line, lineno, "comment line")
        try:
            if stripped[:1] == b"(" and (b"#" in stripped or b"[" not in stripped):
                frame = parse_log_line(stripped, self._frame_id, self._channel)
                timed, relative, screen = True, False, False
            else:
                frame, timed, relative = parse_screen_line(
                    stripped, self._frame_id, self._channel, self.clock
                )
                screen = True
        except LineError as exc:
            return self._bad(line, lineno, str(exc))
        self._after_error = frame.is_error
        self.frames += 1
        if relative:
            timed, settled = self._times.take(frame)
            self._adopt(settled)
        elif screen and timed and self.time_base is None and frame.time >= RELATIVE_LIMIT:
            # A dated screen time settles the base for the screen times after it; the
            # base of -L times is judged from the first of them (``base_of_times``).
            self._times.base = ABSOLUTE
        if timed:
            if self.first_time is None:
                self.first_time = frame.time
            self.last_time = frame.time
        if not (frame.is_error or self.wanted_ids is None or frame.can_id in self.wanted_ids):
            self.frames_skipped += 1
            return None
        return frame

    # -- relative (-tz) and delta (-td) screen times -----------------------------------------

    @property
    def time_base(self) -> str | None:
        """How the times were written: ABSOLUTE, RELATIVE_TO_START (-tz) or DELTA (-td)."""
        return self._times.base

    def _adopt(self, times: list[float]) -> None:
        """The times of held frames, now settled: they widen the span."""
        if times:
            if self.first_time is None or times[0] < self.first_time:
                self.first_time = times[0]
            self.last_time = times[-1]

    def finish(self) -> list[InputItem]:
        """The end of the input: items still held while the time base was open."""
        self._adopt(self._times.settle())
        held = self._release()
        if self.bad_lines_not_shown:
            held.append(
                diagnostic(
                    self.last_time if self.last_time is not None else 0.0,
                    self.source,
                    BAD_LINE,
                    f"{self.bad_lines_not_shown:,} more bad lines not listed (the file is not "
                    "candump output)",
                    count=self.bad_lines_not_shown,
                )
            )
        return held

    def base_of_times(self) -> str | None:
        """The time base of what was read (None when no line had a time)."""
        if self.time_base is None and self.first_time is not None:
            return ABSOLUTE if self.first_time >= RELATIVE_LIMIT else RELATIVE_TO_START
        return self.time_base

    def _release(self) -> list[InputItem]:
        held, self._held = self._held, []
        return held


class CandumpReader(InputReader):
    """A candump text file (``-L`` or default output), plain or gzip-compressed."""

    format_name = "candump"

    def __init__(
        self,
        path: str,
        *,
        wanted_ids: Iterable[int] | None = None,
        block_size: int = BLOCK_SIZE,
    ) -> None:
        super().__init__(path)
        self.block_size = block_size
        self._raw = self._open_binary()
        self._blocks, self.problems = open_lines(self._raw, block_size)
        self.parser = CandumpParser(self.source, wanted_ids=wanted_ids)

    def __iter__(self) -> Iterator[InputItem]:
        for items in self.batches(self.block_size):
            yield from items

    def batches(self, size: int) -> Iterator[list[InputItem]]:
        """The items of each block of lines (in lists of at most ``size``)."""
        parser = self.parser
        raw = self._raw
        problems = self.problems
        parser.frame_runs = self.frame_runs
        reported = 0
        for block in line_blocks(self._blocks, self.block_size):
            items = parser.parse_block(block)
            self.position_bytes = raw.tell()
            self.first_time, self.last_time = parser.first_time, parser.last_time
            while reported < len(problems):
                items.append(self._damage(problems[reported]))
                reported += 1
            if self.frame_runs and items:
                yield from by_frames(items, size)
            elif len(items) <= size:
                yield items  # also when empty: the caller's progress moves on
            else:
                for start in range(0, len(items), size):
                    yield items[start : start + size]
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
        return diagnostic(
            parser.last_time or 0.0,
            self.source,
            BAD_LINE,
            f"after line {parser.lines}: {problem}",
            line=parser.lines,
        )

    @property
    def stats(self) -> dict[str, int]:
        return self.parser.stats
