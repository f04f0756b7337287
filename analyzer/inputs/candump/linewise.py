"""candump lines one at a time: frames, bad lines and notes, counted; screen-time bases."""

from __future__ import annotations

from collections.abc import Callable, Iterable

from analyzer.inputs.base import ABSOLUTE, RELATIVE_TO_START, InputItem
from analyzer.inputs.candump.line import (
    RELATIVE_LIMIT,
    IdInfo,
    LineError,
    id_info,
    parse_log_line,
    parse_screen_line,
)
from analyzer.inputs.candump.times import ScreenTimes
from analyzer.inputs.detect import FORMATS, sniff_format
from analyzer.inputs.textlines import MAX_LINE
from analyzer.protocol.types import BAD_LINE, Event, diagnostic

RAW_LIMIT = 200  # bytes of a bad line kept in its diagnostic
FOREIGN_HEAD = 20  # first bad lines looked at to tell what a file that is no candump is
FOREIGN_BAD = 10  # bad lines (with under a tenth as many frames) that make it no candump
# ID texts and channel names kept in the caches; beyond that (a log of random IDs) a text
# is looked at anew each time, and memory stays flat.
MAX_CACHED_IDS = 20_000
MAX_CACHED_CHANNELS = 10_000


class CandumpLineParser:
    """The line-by-line part of ``CandumpParser``: each line looked at on its own with the
    line parser, the counters, the ID and channel caches, the note on a file that is no
    candump, and the frames held until the base of ``-tz`` / ``-td`` screen times is known.
    """

    def __init__(
        self,
        source: str,
        *,
        wanted_ids: Iterable[int] | None = None,
        clock: Callable[[], float] | None = None,
    ) -> None:
        self.source = source
        self.wanted_ids = None if wanted_ids is None else frozenset(wanted_ids)
        self.clock = clock
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

    def _channel(self, text: bytes) -> str:
        name = self._channels.get(text)
        if name is None:
            name = text.decode("ascii", "replace")
            if len(self._channels) < MAX_CACHED_CHANNELS:
                self._channels[text] = name
        return name

    # -- lines -----------------------------------------------------------------------------

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
