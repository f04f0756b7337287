"""Log formats read through python-can: Vector ASC and BLF, PCAN TRC, python-can CSV, MF4."""

from __future__ import annotations

import gzip
import io
from collections.abc import Iterator
from typing import IO, Any

from analyzer.errors import UsageError
from analyzer.inputs.base import InputItem, InputReader
from analyzer.protocol.types import BAD_FRAME, BAD_LINE, CanFrame, diagnostic

# format -> (python-can reader class name, text file?)
READERS: dict[str, tuple[str, bool]] = {
    "asc": ("ASCReader", True),
    "blf": ("BLFReader", False),
    "trc": ("TRCReader", True),
    "csv": ("CSVReader", True),
    "mf4": ("MF4Reader", False),
}


def frame_from_message(msg: Any) -> CanFrame:
    """A ``can.Message`` -> CanFrame (remote frames carry no data)."""
    channel = msg.channel
    return CanFrame(
        float(msg.timestamp or 0.0),
        int(msg.arbitration_id),
        b"" if msg.is_remote_frame else bytes(msg.data or b""),
        bool(msg.is_extended_id),
        "" if channel is None else str(channel),
        bool(msg.is_remote_frame),
        bool(msg.is_error_frame),
        bool(msg.is_fd),
        "rx" if msg.is_rx else "tx",
    )


class PythonCanReader(InputReader):
    """Frames of a python-can log file; a read error ends the file with a diagnostic."""

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
        reader_class = getattr(can, class_name)
        self._raw = self._open_binary()
        handle: IO[Any] = self._raw
        if self._raw.read(2) == b"\x1f\x8b":
            handle = gzip.GzipFile(fileobj=self._raw, mode="rb")  # type: ignore[assignment]
            self._closers.append(handle)
        self._raw.seek(0)
        if text:
            handle = io.TextIOWrapper(handle, encoding="utf-8", errors="replace", newline=None)
            self._closers.append(handle)
        options: dict[str, Any] = {}
        if fmt == "asc":
            options["relative_timestamp"] = not _asc_date_readable(can, handle)
        try:
            self._reader = reader_class(handle, **options)
        except ImportError as exc:
            self.close()
            raise UsageError(
                f"reading .{fmt} files needs an extra package: {exc.name or exc}"
            ) from None
        except Exception as exc:
            self.close()
            raise UsageError(f"cannot read {path} as {fmt}: {_why(exc)}") from None
        self._closers.append(self._reader)
        self.frames = 0

    def __iter__(self) -> Iterator[InputItem]:
        raw = self._raw
        iterator = iter(self._reader)
        while True:
            try:
                msg = next(iterator)
            except StopIteration:
                break
            except Exception as exc:  # python-can gives up on the first damaged record
                kind = BAD_LINE if READERS[self.format_name][1] else BAD_FRAME
                yield diagnostic(
                    self.last_time or 0.0,
                    self.source,
                    kind,
                    f"reading stopped after frame {self.frames}: {_why(exc)}",
                    frames_read=self.frames,
                )
                break
            frame = frame_from_message(msg)
            self.frames += 1
            if self.first_time is None:
                self.first_time = frame.time
            self.last_time = frame.time
            if not self.frames & 0xFF:
                self.position_bytes = _tell(raw)
            yield frame
        self.position_bytes = self.size_bytes or _tell(raw)
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

    @property
    def stats(self) -> dict[str, int]:
        return {"frames": self.frames}


def _asc_date_readable(can: Any, handle: IO[str]) -> bool:
    """Whether the ``date`` header of an ASC file gives absolute times (then they are used)."""
    try:
        head = handle.read(4096)
        handle.seek(0)
    except (OSError, ValueError):
        return False
    for line in head.splitlines()[:10]:
        words = line.strip().split(None, 2)
        if len(words) == 3 and words[0].lower() == "date":
            try:
                can.ASCReader._datetime_to_timestamp(words[2])
                return True
            except Exception:  # any unexpected date layout: keep times relative
                return False
    return False


def _tell(handle: IO[bytes]) -> int:
    try:
        return handle.tell()
    except (OSError, ValueError):
        return 0


def _why(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__
