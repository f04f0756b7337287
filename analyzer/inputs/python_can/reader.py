"""Log formats read through python-can: Vector ASC, PCAN TRC, python-can CSV, MF4.

(Vector BLF has a reader of its own: ``analyzer.inputs.blf``.)
"""

from __future__ import annotations

import gzip
from collections.abc import Iterator
from typing import IO, Any

from analyzer.errors import UsageError
from analyzer.inputs.base import DELTA, InputItem, InputReader, time_problem
from analyzer.inputs.python_can.text_logs import LineFeed, TextLogReading, text_lines
from analyzer.library_log import LibraryLog, library_log
from analyzer.protocol.can_message import frame_from_message
from analyzer.protocol.types import BAD_FRAME, BAD_LINE, CanFrame, Event, diagnostic

# format -> (python-can reader class name, text file?)

READERS: dict[str, tuple[str, bool]] = {
    "asc": ("ASCReader", True),
    "trc": ("TRCReader", True),
    "csv": ("CSVReader", True),
    "mf4": ("MF4Reader", False),
}


class PythonCanReader(InputReader):
    """Frames of a python-can log file, plain or gzip-compressed.

    ASC, TRC and CSV are read line by line (``text_logs``): a damaged line becomes
    a ``bad_line`` diagnostic with its line number and reading goes on. An ASC file whose
    header says ``timestamps relative`` holds the time since the previous frame: those
    are added up from the ``date`` in the header, as can-utils' ``asc2log`` does.
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
        if fmt == "mf4" and handle is self._raw and self.size_bytes:
            from analyzer.inputs.python_can.mf4_check import mf4_problem

            problem = mf4_problem(handle, self.size_bytes)
            if problem:
                self.close()
                raise UsageError(f"cannot read {self.path} as mf4: {problem}")
        with library_log(self._log):
            self._reader = self._check(lambda: self._reader_class(handle))
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
                yield from self._library_messages()  # what it said before it gave up
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
