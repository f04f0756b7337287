"""Log formats read through python-can: Vector ASC and BLF, PCAN TRC, python-can CSV, MF4."""

from __future__ import annotations

import gzip
import struct
from collections.abc import Iterator
from typing import IO, Any

from analyzer.errors import UsageError
from analyzer.inputs.base import DELTA, InputItem, InputReader, time_problem
from analyzer.inputs.python_can.library_log import LibraryLog, library_log
from analyzer.inputs.python_can.text_logs import LineFeed, TextLogReading, text_lines
from analyzer.protocol.can_message import frame_from_message
from analyzer.protocol.types import BAD_FRAME, BAD_LINE, CanFrame, Event, diagnostic

# format -> (python-can reader class name, text file?)
_BLF_OBJECT_HEADER = 16  # signature, header size and version, object size and type
_BLF_FILE_HEADER = struct.Struct("<4sL")  # python-can's blf.py: "LOGG", header size
_BLF_HEADER_MIN = 72  # python-can reads this much (its FILE_HEADER_STRUCT) before the rest
_READ_PIECE = 1 << 20  # a larger read is made in pieces of this size

READERS: dict[str, tuple[str, bool]] = {
    "asc": ("ASCReader", True),
    "blf": ("BLFReader", False),
    "trc": ("TRCReader", True),
    "csv": ("CSVReader", True),
    "mf4": ("MF4Reader", False),
}


class PythonCanReader(InputReader):
    """Frames of a python-can log file, plain or gzip-compressed.

    ASC, TRC and CSV are read line by line (``text_logs``): a damaged line becomes
    a ``bad_line`` diagnostic with its line number and reading goes on. An ASC file whose
    header says ``timestamps relative`` holds the time since the previous frame: those
    are added up from the ``date`` in the header, as can-utils' ``asc2log`` does. A BLF
    file cut off inside an object (a logger that lost power) keeps every frame before
    the cut and says so.
    """

    def __init__(self, path: str, fmt: str) -> None:
        super().__init__(path)
        if fmt not in READERS:
            raise UsageError(f"python-can cannot read format {fmt!r}")
        self.format_name = fmt
        class_name, text = READERS[fmt]
        try:
            import can
        except ImportError:  # pragma: no cover - python-can is a dependency
            raise UsageError(f"reading .{fmt} files needs python-can") from None
        self._can = can
        self._reader_class = getattr(can, class_name)
        self._raw = self._open_binary()
        self._log = LibraryLog()
        self.frames = 0
        self._text: TextLogReading | None = None
        self._watch: _ShortReads | None = None
        if text:
            self._damage: list[str] = []
            lines = text_lines(self._raw, self._damage)
            self._text = TextLogReading(
                fmt, lines, self._make_text_reader, self.source, self._damage
            )
            self.time_base = self._text.time_base
            self._start = _asc_start(can, self._text.header) if fmt == "asc" else 0.0
            return
        handle: IO[bytes] = self._raw
        if self._raw.read(2) == b"\x1f\x8b":
            handle = gzip.GzipFile(fileobj=self._raw, mode="rb")  # type: ignore[assignment]
            self._closers.append(handle)
        self._raw.seek(0)
        if fmt == "blf":  # BLF objects are read one by one: a cut shows as a short read
            if handle is self._raw:
                try:
                    _check_blf_header(handle, self.path, self.size_bytes)
                except UsageError:
                    self.close()
                    raise
            self._watch = _ShortReads(handle)
        elif fmt == "mf4" and handle is self._raw and self.size_bytes:
            from analyzer.inputs.python_can.mf4_check import mf4_problem

            problem = mf4_problem(handle, self.size_bytes)
            if problem:
                self.close()
                raise UsageError(f"cannot read {self.path} as mf4: {problem}")
        watched = self._watch if self._watch is not None else handle
        with library_log(self._log):
            self._reader = self._check(lambda: self._reader_class(watched))
        self._closers.append(self._reader)

    def _check(self, make: Any) -> Any:
        try:
            return make()
        except ImportError as exc:
            self.close()
            raise UsageError(
                f"reading .{self.format_name} files needs an extra package: {exc.name or exc}"
            ) from None
        except Exception as exc:
            why = _why(exc)
        # Raised here, not in the except block: the half-made reader goes with ``exc``.
        self.close()
        raise UsageError(f"cannot read {self.path} as {self.format_name}: {why}")

    def _make_text_reader(self, feed: LineFeed) -> Any:
        options: dict[str, Any] = {}
        if self.format_name == "asc":
            # Absolute times get the header's (or a trigger block's) date added by
            # python-can; time differences come out as written and are added up here.
            options["relative_timestamp"] = self.time_base == DELTA or not self._start
        return self._reader_class(feed, **options)

    def __iter__(self) -> Iterator[InputItem]:
        log = self._log
        with library_log(log):
            items = self._text_items(self._text) if self._text else self._binary_items()
            for item in items:
                yield item
                if log.messages:
                    yield from self._library_messages()
            yield from self._library_messages()
        self.position_bytes = self.size_bytes or _tell(self._raw)
        if not self.frames and self.size_bytes:
            # A non-empty file that gave no frame is worth saying so (a file of another
            # format gives one damaged line after another, or none at all).
            kind = BAD_LINE if READERS[self.format_name][1] else BAD_FRAME
            yield diagnostic(
                0.0,
                self.source,
                kind,
                f"no CAN frame could be read from {self.size_bytes:,} bytes read as "
                f"{self.format_name.upper()}; check the file's format (--format)",
                frames_read=0,
            )

    def _library_messages(self) -> Iterator[Event]:
        """What python-can / asammdf logged (a line or record they skipped, mostly)."""
        text = self._text
        for message in self._log.take():
            if text is None:
                detail = f"after frame {self.frames}: {message}"
                yield diagnostic(self.last_time or 0.0, self.source, BAD_FRAME, detail)
            else:
                line = text.feed.lineno
                detail = f"line {line}: {message}"
                yield diagnostic(self.last_time or 0.0, self.source, BAD_LINE, detail, line=line)

    def _text_items(self, text: TextLogReading) -> Iterator[InputItem]:
        raw = self._raw
        delta = text.time_base == DELTA
        start = self._start
        elapsed = 0.0
        for msg in text.messages():
            if isinstance(msg, Event):
                if delta and msg.fields.get("kind") == BAD_LINE and "line" in msg.fields:
                    step = _leading_number(text.feed.last)  # its time still passed
                    if step > 0 and time_problem(start + elapsed + step) is None:
                        elapsed += step  # (a damaged time, 1e309, is no time passed)
                yield msg
                continue
            frame = frame_from_message(msg)
            problem = time_problem(frame.time)
            if delta and problem is None:
                problem = time_problem(start + elapsed + frame.time)
                if problem is None:
                    elapsed += frame.time
                    frame.time = start + elapsed
            if problem:  # a damaged number that python-can took for a time
                yield text.bad_line(text.feed.lineno, text.feed.last, ValueError(problem))
                continue
            yield from self._count(frame, raw)
            text.last_time = frame.time

    def _binary_items(self) -> Iterator[InputItem]:
        raw = self._raw
        iterator = iter(self._reader)
        while True:
            try:
                msg = next(iterator)
            except StopIteration:
                break
            except Exception as exc:  # python-can gives up on the first damaged record
                yield diagnostic(
                    self.last_time or 0.0,
                    self.source,
                    BAD_FRAME,
                    f"reading stopped after frame {self.frames}: {_why(exc)}",
                    frames_read=self.frames,
                )
                return
            frame = frame_from_message(msg)
            problem = time_problem(frame.time)
            if problem:  # a damaged time field or start date
                yield diagnostic(
                    self.last_time or 0.0,
                    self.source,
                    BAD_FRAME,
                    f"frame {self.frames + 1} skipped: its {problem}",
                    frames_read=self.frames,
                )
                continue
            yield from self._count(frame, raw)
        cut = self._watch.cut_at if self._watch is not None else None
        tail = getattr(self._reader, "_tail", b"")
        if cut is not None or tail:
            where = f" at byte {cut:,}" if cut is not None else ""
            yield diagnostic(
                self.last_time or 0.0,
                self.source,
                BAD_FRAME,
                f"the {self.format_name.upper()} file is cut off inside an object{where} "
                f"(as a logger that lost power leaves it): the {self.frames:,} frames "
                "before the cut were read",
                frames_read=self.frames,
            )

    def _count(self, frame: CanFrame, raw: IO[bytes]) -> Iterator[CanFrame]:
        self.frames += 1
        if self.first_time is None:
            self.first_time = frame.time
        self.last_time = frame.time
        if not self.frames & 0xFF:
            self.position_bytes = _tell(raw)
        yield frame

    @property
    def stats(self) -> dict[str, int]:
        if self._text is None:
            return {"frames": self.frames}
        return {
            "lines": self._text.feed.lineno,
            "frames": self.frames,
            "bad_lines": self._text.bad_lines,
        }


def _check_blf_header(handle: IO[bytes], path: str, size: int | None) -> None:
    """Refuse a BLF file whose header claims more bytes than the file has (python-can
    would allocate what it claims before reading it)."""
    head = handle.read(_BLF_FILE_HEADER.size)
    handle.seek(0)
    if len(head) < _BLF_FILE_HEADER.size or head[:4] != b"LOGG":
        return  # python-can says what is wrong with it
    _, header_size = _BLF_FILE_HEADER.unpack(head)
    if header_size < _BLF_HEADER_MIN or (size is not None and header_size > size):
        raise UsageError(
            f"cannot read {path} as blf: its header claims to be {header_size:,} bytes long "
            f"in a file of {size:,} bytes (a damaged or not a BLF file)"
        )


class _ShortReads:
    """A binary file that notes where a read first came back shorter than asked, and
    reads a large request in pieces (a damaged size field costs no memory it does not
    fill)."""

    def __init__(self, handle: IO[bytes]) -> None:
        self._handle = handle
        self.cut_at: int | None = None
        self._offset = 0
        self._after_header = False

    def read(self, size: int = -1) -> bytes:
        if size is None or size < 0:
            data = self._handle.read()
        elif size <= _READ_PIECE:
            data = self._handle.read(size)
        else:
            pieces = []
            left = size
            while left and (piece := self._handle.read(min(left, _READ_PIECE))):
                pieces.append(piece)
                left -= len(piece)
            data = b"".join(pieces)
        # The end of the file is fine between objects (an empty read of the next header)
        # and at the padding after the last one (under 4 bytes).
        short = len(data) < size and (bool(data) or self._after_header) and size >= 4
        if short and self.cut_at is None:
            self.cut_at = self._offset + len(data)
        self._after_header = size == _BLF_OBJECT_HEADER and len(data) == size
        self._offset += len(data)
        return data

    def close(self) -> None:
        self._handle.close()


def _asc_start(can: Any, header: list[str]) -> float:
    """The time of the ``date`` header line of an ASC file (0.0 when unreadable)."""
    for line in header:
        words = line.strip().split(None, 2)
        if len(words) == 3 and words[0].lower() == "date":
            try:
                return float(can.ASCReader._datetime_to_timestamp(words[2]))
            except Exception:  # any unexpected date layout: times stay relative
                return 0.0
    return 0.0


def _leading_number(line: str) -> float:
    try:
        return float(line.split(None, 1)[0])
    except (ValueError, IndexError):
        return 0.0


def _tell(handle: IO[bytes]) -> int:
    try:
        return handle.tell()
    except (OSError, ValueError):
        return 0


def _why(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__
