"""candump text: ``-L`` log lines and the default screen output, parsed tolerantly and fast."""

from __future__ import annotations

import datetime
import itertools
from binascii import unhexlify
from collections.abc import Callable, Iterable, Iterator

from analyzer.inputs.base import InputItem, InputReader
from analyzer.inputs.python_can_text import ABSOLUTE, DELTA, RELATIVE_TO_START
from analyzer.inputs.textlines import BLOCK_SIZE, MAX_LINE, open_lines, split_blocks
from analyzer.protocol.types import BAD_LINE, CanFrame, Event, diagnostic

CAN_ERR_FLAG = 0x20000000
CAN_EFF_MASK = 0x1FFFFFFF
RAW_LIMIT = 200  # bytes of a bad line kept in its diagnostic
MAX_CLASSIC_HEX = 16  # 8 data bytes
MAX_FD_HEX = 128  # 64 data bytes
_DIRECTIONS = {b"R": "rx", b"r": "rx", b"T": "tx", b"t": "tx"}
_HEXDIGITS = frozenset(b"0123456789abcdefABCDEF")
_NAN = float("nan")
_DIGITS = b"0123456789"
RELATIVE_LIMIT = 1e8  # a screen time below this is no date: -tz or -td
FOREIGN_HEAD = 20  # first bad lines looked at to tell what a file that is no candump is
FOREIGN_BAD = 10  # bad lines (with under a tenth as many frames) that make it no candump
DECIDE_AFTER = 50  # relative times looked at before -tz and -td are told apart by rate
_HEX_TEXT = b"0123456789abcdefABCDEF"

# Parsed ID text -> (can_id, extended, is_error, wanted); None marks an invalid ID text.
IdInfo = tuple[int, bool, bool, bool]


# ID texts kept in the caches; beyond that (a log of random IDs) an ID is classified anew
# each time, which is still the fast path, and memory stays flat.
MAX_CACHED_IDS = 20_000


class LineError(ValueError):
    """Why a line is not a CAN frame (becomes the detail of a bad_line diagnostic)."""


class CandumpParser:
    """Turns candump text lines into CanFrames and bad_line diagnostics.

    Both ``candump -L`` (``(1436509052.249713) can0 030F0001#EB900C...``, with optional
    ``R``/``T`` suffix, ``#R`` remote frames, ``##`` CAN FD frames and error frames) and
    the default output (``can0  030F0001   [8]  EB 90 0C ...``, with the ``-t``, ``-x``,
    ``-a`` and ``-e`` variants) are understood, line by line.

    ``wanted_ids``: when given, valid frames with other IDs are checked and counted
    (``frames_skipped``) but not returned, which keeps decoding a busy bus cheap; error
    frames are always returned. ``clock`` gives the time of lines without a timestamp
    (live input); without it they get 0.0.
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
        self._skip: set[bytes] = set()  # ID texts of valid frames that are not wanted
        self._want: dict[bytes, IdInfo] = {}  # ID texts of frames to return
        self._channels: dict[bytes, str] = {}
        self._after_error = False
        # How the times were written: ABSOLUTE, RELATIVE_TO_START (-tz) or DELTA (-td).
        self.time_base: str | None = None
        self._elapsed = 0.0
        self._raw_times: list[float] = []  # relative times while the base is open
        self._undecided: list[tuple[int, CanFrame]] = []  # held frames and their time index
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

    def _id_info(self, text: bytes) -> IdInfo | None:
        info: IdInfo | None = None
        if 0 < len(text) <= 8 and not text.translate(None, _HEX_TEXT):
            value = int(text, 16)
            extended = len(text) > 3
            error = extended and bool(value & CAN_ERR_FLAG)
            can_id = value & CAN_EFF_MASK
            if value <= CAN_EFF_MASK or error:
                wanted = error or self.wanted_ids is None or can_id in self.wanted_ids
                info = (can_id, extended, error, wanted)
        if len(self._ids) < MAX_CACHED_IDS:  # a file of random IDs must not grow the caches
            self._ids[text] = info
            if info is not None:
                if info[3]:
                    self._want[text] = info
                else:
                    self._skip.add(text)
        return info

    def _unwanted(self, text: bytes) -> bool:
        """An ID text not seen before (or no longer cached): a valid ID that is not wanted?"""
        info = self._id_info(text)
        return info is not None and not info[3]

    def _channel(self, text: bytes) -> str:
        name = self._channels.get(text)
        if name is None:
            name = text.decode("ascii", "replace")
            if len(self._channels) < 10_000:
                self._channels[text] = name
        return name

    # -- lines -----------------------------------------------------------------------------

    def parse_lines(self, lines: list[bytes]) -> list[InputItem]:
        """Parse a list of lines (without line ends); returns frames and diagnostics."""
        out: list[InputItem] = []
        append = out.append
        skip = self._skip
        want = self._want
        ids = self._ids
        channels = self._channels
        wanted = self.wanted_ids
        directions = _DIRECTIONS
        digits = _DIGITS
        lineno = self.lines
        skipped = 0
        # Timestamp texts of the first and last of a run of skipped frames, parsed lazily.
        run_start = pending = b""
        for line in lines:
            lineno += 1
            # Fast path: a well-formed ``candump -L`` line, ``(time) channel id#data [R|T]``.
            # A timestamp is checked by deleting its digits: ``(.)`` must remain.
            parts = line.split(b" ")
            nparts = len(parts)
            if nparts == 3:
                stamp, channel, frame = parts
                direction = ""
            elif nparts == 4 and parts[3] in directions:
                stamp, channel, frame, suffix = parts
                direction = directions[suffix]
            else:
                stamp = b""
            if stamp:
                id_text, sharp, data = frame.partition(b"#")
                if id_text in skip or (
                    sharp
                    and id_text not in want
                    and id_text not in ids
                    and (
                        # not cached (a log of very many IDs): an extended ID that
                        # is not wanted is told apart here, without the slow path
                        (
                            wanted is not None
                            and len(id_text) == 8
                            and not id_text.translate(None, _HEX_TEXT)
                            and (value := int(id_text, 16)) <= CAN_EFF_MASK
                            and value not in wanted
                        )
                        if len(ids) >= MAX_CACHED_IDS
                        else self._unwanted(id_text)
                    )
                ):
                    if (
                        sharp
                        and len(data) <= MAX_CLASSIC_HEX
                        and len(stamp) > 3
                        and stamp[:1] == b"("
                        and stamp[-1:] == b")"
                        and stamp.translate(None, digits) == b"(.)"
                    ):
                        try:
                            unhexlify(data)
                        except ValueError:
                            pass
                        else:
                            if not skipped:
                                run_start = stamp
                            skipped += 1
                            pending = stamp
                            continue
                elif sharp:
                    info = want.get(id_text)
                    if info is not None and stamp[:1] == b"(" and stamp[-1:] == b")":
                        try:
                            ts = float(stamp[1:-1])
                            if len(data) <= MAX_CLASSIC_HEX:
                                payload = unhexlify(data)
                                is_fd = is_remote = False
                            else:
                                payload, is_fd, is_remote = _log_payload(data)
                        except ValueError:  # LineError too; the slow path says why
                            ts = _NAN
                        if -1e15 < ts < 1e15:
                            if skipped:
                                self._count_skipped(skipped, run_start, pending)
                                skipped = 0
                            self.frames += 1
                            if self.first_time is None:
                                self.first_time = ts
                            self.last_time = ts
                            self._after_error = info[2]
                            append(
                                CanFrame(
                                    ts,
                                    info[0],
                                    payload,
                                    info[1],
                                    channels.get(channel) or self._channel(channel),
                                    is_remote,
                                    info[2],
                                    is_fd,
                                    direction,
                                    _remote_dlc(data) if is_remote else 0,
                                )
                            )
                            continue
            # Everything else: unseen IDs, other layouts, blanks, comments, damaged lines.
            if skipped:
                self._count_skipped(skipped, run_start, pending)
                skipped = 0
            item = self._slow_line(line, lineno)
            if item is not None:
                append(item)
        if skipped:
            self._count_skipped(skipped, run_start, pending)
        self.lines = lineno
        if self._held or self._undecided:  # frames wait for their time base (-tz / -td)
            self._held.extend(out)
            return self._release() if self.time_base is not None else []
        return out

    def _count_skipped(self, count: int, first: bytes, last: bytes) -> None:
        """A run of ``count`` skipped frames, with the timestamp texts of its ends."""
        self.frames += count
        self.frames_skipped += count
        self._after_error = False
        if self.first_time is None:
            self.first_time = float(first[1:-1])
        self.last_time = float(last[1:-1])

    def parse_line(self, line: bytes) -> InputItem | None:
        """Parse one line (line end allowed); None for blank lines and skipped frames."""
        items = self.parse_lines([line.rstrip(b"\r\n")])
        return items[0] if items else None

    def _payload(self, data: bytes) -> tuple[bytes, bool, bool] | None:
        """The part after ``#`` of a ``-L`` frame -> (data, is_fd, is_remote), None if bad."""
        try:
            return _log_payload(data)
        except LineError:
            return None

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
                frame, timed, relative = self._log_line(stripped), True, False
            else:
                frame, timed, relative = self._screen_line(stripped)
        except LineError as exc:
            return self._bad(line, lineno, str(exc))
        self._after_error = frame.is_error
        self.frames += 1
        if relative:
            timed = self._relative_time(frame)
        elif timed and self.time_base is None and frame.time >= RELATIVE_LIMIT:
            self.time_base = ABSOLUTE
        if timed:
            if self.first_time is None:
                self.first_time = frame.time
            self.last_time = frame.time
        if not (frame.is_error or self.wanted_ids is None or frame.can_id in self.wanted_ids):
            self.frames_skipped += 1
            return None
        return frame

    def _frame_id(self, text: bytes) -> IdInfo:
        info = self._ids[text] if text in self._ids else self._id_info(text)
        if info is None:
            raise LineError(f"bad CAN ID {text.decode('ascii', 'replace')!r}")
        return info

    def _log_line(self, line: bytes) -> CanFrame:
        """A ``candump -L`` line the fast path did not take: find out what is wrong."""
        close = line.find(b")")
        if close < 0:
            raise LineError("timestamp not closed by ')'")
        ts = _timestamp(line[1:close])
        parts = line[close + 1 :].split()
        if len(parts) < 2:
            raise LineError("expected '(time) channel id#data'")
        if len(parts) > 3 or (len(parts) == 3 and parts[2] not in _DIRECTIONS):
            raise LineError("unexpected text after the frame")
        frame = parts[1]
        h = frame.find(b"#")
        if h < 0:
            raise LineError("no '#' between CAN ID and data")
        info = self._frame_id(frame[:h])
        payload, is_fd, is_remote = _log_payload(frame[h + 1 :])
        direction = _DIRECTIONS[parts[2]] if len(parts) == 3 else ""
        return CanFrame(
            ts,
            info[0],
            payload,
            info[1],
            self._channel(parts[0]),
            is_remote,
            info[2],
            is_fd,
            direction,
            _remote_dlc(frame[h + 1 :]) if is_remote else 0,
        )

    def _screen_line(self, line: bytes) -> tuple[CanFrame, bool, bool]:
        """The default ``candump`` output: ``[(time)] can0 [RX - -] 123 [8] 11 22 ...``.

        Returns the frame, whether its time is known (from the line or the clock) and
        whether that time is a relative one (-tz or -td: no date).
        """
        tokens = line.split()
        i = 0
        ts: float | None = None
        dated = False  # ``-t A``: a date and time of day
        if tokens[0][:1] == b"(":
            if tokens[0].endswith(b")"):
                ts = _timestamp(tokens[0][1:-1])
                i = 1
            elif len(tokens) > 1 and tokens[1].endswith(b")"):
                ts = _date_time(tokens[0][1:] + b" " + tokens[1][:-1])
                i = 2
                dated = True
            else:
                raise LineError("timestamp not closed by ')'")
        if len(tokens) < i + 3:
            raise LineError("not a candump line")
        channel = tokens[i]
        i += 1
        direction = ""
        if tokens[i] in (b"RX", b"TX"):
            direction = tokens[i].decode().lower()
            i += 1
            flags = 0
            while i < len(tokens) and flags < 2 and tokens[i] in (b"-", b"B", b"E"):
                i += 1
                flags += 1
        if len(tokens) < i + 2:
            raise LineError("not a candump line")
        info = self._frame_id(tokens[i])
        length_text = tokens[i + 1]
        if not (length_text[:1] == b"[" and length_text[-1:] == b"]"):
            raise LineError("no data length in brackets after the CAN ID")
        inner = length_text[1:-1]
        if not inner.isdigit():
            raise LineError("data length is not a number")
        length = int(inner)
        is_fd = len(inner) == 2  # candump prints CAN FD lengths with two digits
        _check_length(length, is_fd)
        rest = tokens[i + 2 :]
        is_remote = False
        payload = b""
        if rest[:2] == [b"remote", b"request"]:
            is_remote = True
            rest = rest[2:]
        else:
            hex_bytes = rest[:length]
            if len(hex_bytes) < length or not all(
                len(t) == 2 and t[0] in _HEXDIGITS and t[1] in _HEXDIGITS for t in hex_bytes
            ):
                raise LineError(f"expected {length} data bytes in hex")
            payload = bytes(int(t, 16) for t in hex_bytes)
            rest = rest[length:]
        is_error = info[2]
        if rest[:1] == [b"ERRORFRAME"]:
            is_error = True
            rest = rest[1:]
        if rest and not rest[0].startswith(b"'"):  # ``-a`` appends the data as ASCII in quotes
            raise LineError("unexpected text after the data")
        timed = ts is not None or self.clock is not None
        when = ts if ts is not None else (self.clock() if self.clock is not None else 0.0)
        relative = ts is not None and not dated and 0 <= ts < RELATIVE_LIMIT
        frame = CanFrame(
            when,
            info[0],
            payload,
            info[1],
            self._channel(channel),
            is_remote,
            is_error,
            is_fd,
            direction,
            length if is_remote else 0,
        )
        return frame, timed, relative

    # -- relative (-tz) and delta (-td) screen times -----------------------------------------

    def _relative_time(self, frame: CanFrame) -> bool:
        """A ``(000.123456)`` time: since the start (-tz) or since the previous frame (-td).

        The two look alike; until the lines tell them apart (a time going back, or most
        times repeating as a steady rate does under -td) the frames are held. Returns
        whether the frame's time is final now.
        """
        raw = frame.time
        if self.time_base == DELTA:
            self._elapsed += raw
            frame.time = self._elapsed
            return True
        if self.time_base is not None:
            return True
        self._raw_times.append(raw)
        self._undecided.append((len(self._raw_times) - 1, frame))
        times = self._raw_times
        if len(times) >= 2 and times[-1] < times[-2]:
            self._decide(DELTA)
        elif len(times) >= DECIDE_AFTER:
            self._decide(self._steady_guess())
        return False

    def _steady_guess(self) -> str:
        """No time went back: mostly repeated times mean a steady rate under -td."""
        times = self._raw_times[1:]
        repeats = sum(1 for a, b in itertools.pairwise(times) if a == b)
        return DELTA if times and repeats * 2 > len(times) else RELATIVE_TO_START

    def _decide(self, base: str) -> None:
        self.time_base = base
        times = self._raw_times
        if base == DELTA:
            total, sums = 0.0, []
            for t in times:
                total += t
                sums.append(total)
            self._elapsed = total
            for index, frame in self._undecided:
                frame.time = sums[index]
            times = sums
        if times:
            if self.first_time is None or times[0] < self.first_time:
                self.first_time = times[0]
            self.last_time = times[-1]
        self._raw_times = []
        self._undecided = []

    def finish(self) -> list[InputItem]:
        """The end of the input: items still held while the time base was open."""
        if self.time_base is None and self._raw_times:
            self._decide(self._steady_guess())
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


FD_LENGTHS = frozenset((*range(9), 12, 16, 20, 24, 32, 48, 64))


def _check_length(length: int, is_fd: bool) -> None:
    """One rule for both layouts: classic frames hold 0..8 bytes, CAN FD the DLC lengths."""
    if not is_fd and length > 8:
        raise LineError(f"data length {length} too large for a classic CAN frame (at most 8)")
    if is_fd and length not in FD_LENGTHS:
        raise LineError(f"{length} data bytes is no CAN FD length (0..8, 12, 16, ..., 64)")


def _timestamp(text: bytes) -> float:
    try:
        value = float(text)
    except ValueError:
        raise LineError("bad timestamp") from None
    if not -1e15 < value < 1e15:
        raise LineError("bad timestamp")
    return value


def _date_time(text: bytes) -> float:
    """``candump -t A`` times: ``2015-07-10 08:17:32.249713`` in local time."""
    try:
        return datetime.datetime.strptime(text.decode("ascii"), "%Y-%m-%d %H:%M:%S.%f").timestamp()
    except (ValueError, UnicodeDecodeError, OverflowError, OSError):
        raise LineError("bad date/time stamp") from None


def _hex(text: bytes, limit: int, what: str) -> bytes:
    if len(text) > limit:
        raise LineError(f"{what}: more than {limit // 2} data bytes")
    if len(text) & 1:
        raise LineError(f"{what}: odd number of hex digits")
    if not all(c in _HEXDIGITS for c in text):
        raise LineError(f"{what}: data is not hex")
    return unhexlify(text)


def _log_payload(data: bytes) -> tuple[bytes, bool, bool]:
    """The text after ``id#`` -> (data, is_fd, is_remote); LineError says what is wrong."""
    if data[:1] == b"#":  # CAN FD: ##<flags><data>
        if data[1:2] == b"#":
            raise LineError("CAN XL frames are not supported")
        if len(data) < 2 or data[1] not in _HEXDIGITS:
            raise LineError("CAN FD frame without its flags digit")
        payload = _hex(data[2:], MAX_FD_HEX, "CAN FD frame")
        _check_length(len(payload), True)
        return payload, True, False
    if data[:1] in (b"R", b"r"):  # remote request, optionally with its DLC: R, R5, R5_9
        rest = data[1:].split(b"_", 1)[0]
        if rest and not (len(rest) == 1 and rest in b"012345678"):
            raise LineError("bad DLC of a remote frame")
        return b"", False, True
    under = data.find(b"_")  # len8_dlc: 8 data bytes and a DLC 9..F, e.g. 1122334455667788_C
    if under >= 0:
        dlc = data[under + 1 :]
        if len(dlc) != 1 or dlc not in b"9ABCDEFabcdef" or under != MAX_CLASSIC_HEX:
            raise LineError("bad DLC suffix")
        data = data[:under]
    return _hex(data, MAX_CLASSIC_HEX, "CAN frame"), False, False


def _remote_dlc(data: bytes) -> int:
    """The DLC a ``-L`` remote frame requests (``R5`` -> 5); a bare ``R`` requests 0."""
    digit = data[1:2]
    return int(digit) if digit.isdigit() else 0


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
        parser = self.parser
        raw = self._raw
        problems = self.problems
        reported = 0
        for lines in split_blocks(self._blocks, self.block_size):
            items = parser.parse_lines(lines)
            self.position_bytes = raw.tell()
            self.first_time, self.last_time = parser.first_time, parser.last_time
            yield from items
            while reported < len(problems):
                yield self._damage(problems[reported])
                reported += 1
        yield from parser.finish()
        self.first_time, self.last_time = parser.first_time, parser.last_time
        self.time_base = parser.base_of_times()
        self.notes.extend(parser.notes)
        while reported < len(problems):
            yield self._damage(problems[reported])
            reported += 1
        self.position_bytes = raw.tell()

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
