"""Log formats read through python-can: Vector ASC and BLF, PCAN TRC, python-can CSV, MF4."""

from __future__ import annotations

import gzip
from collections.abc import Iterator
from typing import IO, Any

from analyzer.errors import UsageError
from analyzer.inputs.base import InputItem, InputReader
from analyzer.inputs.python_can_text import DELTA, LineFeed, TextLogReading, text_lines
from analyzer.protocol.types import BAD_FRAME, BAD_LINE, CanFrame, Event, diagnostic

# format -> (python-can reader class name, text file?)
_BLF_OBJECT_HEADER = 16  # signature, header size and version, object size and type

READERS: dict[str, tuple[str, bool]] = {
    "asc": ("ASCReader", True),
    "blf": ("BLFReader", False),
    "trc": ("TRCReader", True),
    "csv": ("CSVReader", True),
    "mf4": ("MF4Reader", False),
}


# python-can interfaces whose error frames are SocketCAN's: error classes in the ID, the
# details in 8 data bytes as linux/can/error.h lays them out.
SOCKETCAN_ERROR_INTERFACES = frozenset({"socketcan", "socketcand", "gs_usb", "virtual"})


def frame_from_message(
    msg: Any, channel: str | None = None, *, socketcan_errors: bool = True
) -> CanFrame:
    """A ``can.Message`` -> CanFrame (remote frames carry no data but keep their DLC).

    ``channel`` names the channel when the message does not (a live bus). An error frame
    of an adapter that encodes errors its own way (``socketcan_errors`` false: PCAN,
    Kvaser, Vector, ...) gets error class 0, an unspecified error; its bytes are kept.
    """
    if channel is None:
        channel = msg.channel
    foreign_error = msg.is_error_frame and not socketcan_errors
    return CanFrame(
        float(msg.timestamp or 0.0),
        0 if foreign_error else int(msg.arbitration_id),
        b"" if msg.is_remote_frame else bytes(msg.data or b""),
        bool(msg.is_extended_id),
        "" if channel is None else str(channel),
        bool(msg.is_remote_frame),
        bool(msg.is_error_frame),
        bool(msg.is_fd),
        "rx" if msg.is_rx else "tx",
        int(msg.dlc or 0) if msg.is_remote_frame else 0,
    )


class PythonCanReader(InputReader):
    """Frames of a python-can log file, plain or gzip-compressed.

    ASC, TRC and CSV are read line by line (``python_can_text``): a damaged line becomes
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
            self._watch = _ShortReads(handle)
        watched = self._watch if self._watch is not None else handle
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
            self.close()
            raise UsageError(
                f"cannot read {self.path} as {self.format_name}: {_why(exc)}"
            ) from None

    def _make_text_reader(self, feed: LineFeed) -> Any:
        options: dict[str, Any] = {}
        if self.format_name == "asc":
            # Absolute times get the header's (or a trigger block's) date added by
            # python-can; time differences come out as written and are added up here.
            options["relative_timestamp"] = self.time_base == DELTA or not self._start
        return self._reader_class(feed, **options)

    def __iter__(self) -> Iterator[InputItem]:
        if self._text is not None:
            yield from self._text_items(self._text)
        else:
            yield from self._binary_items()
        self.position_bytes = self.size_bytes or _tell(self._raw)
        if not self.frames and self.size_bytes:
            # python-can's text readers skip lines they do not understand without a word;
            # a non-empty file that gave nothing is worth saying so.
            kind = BAD_LINE if READERS[self.format_name][1] else BAD_FRAME
            yield diagnostic(
                0.0,
                self.source,
                kind,
                f"no CAN frame could be read from {self.size_bytes:,} bytes read as "
                f"{self.format_name.upper()}; check the file's format (--format)",
                frames_read=0,
            )

    def _text_items(self, text: TextLogReading) -> Iterator[InputItem]:
        raw = self._raw
        delta = text.time_base == DELTA
        start = self._start
        elapsed = 0.0
        for msg in text.messages():
            if isinstance(msg, Event):
                if delta and msg.fields.get("kind") == BAD_LINE and "line" in msg.fields:
                    elapsed += _leading_number(text.feed.last)  # its time still passed
                yield msg
                continue
            frame = frame_from_message(msg)
            if delta:
                elapsed += frame.time
                frame.time = start + elapsed
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
            yield from self._count(frame_from_message(msg), raw)
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


class _ShortReads:
    """A binary file that notes where a read first came back shorter than asked."""

    def __init__(self, handle: IO[bytes]) -> None:
        self._handle = handle
        self.cut_at: int | None = None
        self._offset = 0
        self._after_header = False

    def read(self, size: int = -1) -> bytes:
        data = self._handle.read(size)
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
