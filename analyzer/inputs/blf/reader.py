"""Vector BLF files, plain or gzip-compressed: CAN frames as columns, every skip said.

The file's log data is read a block at a time (``containers``, ``stream``): runs of
CAN data frames come as ``FrameColumns``, every other CAN frame (remote, error, CAN FD)
as a CanFrame in its place. A damaged object, a header version Vector does not
document, bytes that are no object and a file cut off inside an object each become a
``bad_frame`` diagnostic, and reading goes on after them; objects that carry no CAN
frame (LIN, Ethernet, application texts, markers, ...) are counted and named in a note.
A frame whose time is no time (beyond the year 2242) is a diagnostic too, as for every
other format.
"""

from __future__ import annotations

import gzip
import zlib
from collections import Counter
from collections.abc import Iterator
from typing import IO

from analyzer.errors import UsageError
from analyzer.inputs.base import InputItem, InputReader, by_frames, one_by_one, time_problem
from analyzer.inputs.blf.containers import Containers, read_header
from analyzer.inputs.blf.objects import Skipped
from analyzer.inputs.blf.stream import ObjectStream
from analyzer.inputs.textlines import GZIP_MAGIC
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.types import BAD_FRAME, CanFrame, Event, diagnostic

BLOCK = 1 << 20  # log data read into columns at a time


class BlfReader(InputReader):
    """A Vector BLF file (see the module docstring)."""

    format_name = "blf"

    def __init__(self, path: str) -> None:
        super().__init__(path)
        raw = self._open_binary()
        handle: IO[bytes] = raw
        known_size = self.size_bytes
        if raw.read(2) == GZIP_MAGIC:
            handle = gzip.GzipFile(fileobj=raw, mode="rb")  # type: ignore[assignment]
            self._closers.append(handle)
            known_size = None
        raw.seek(0)
        self._raw = raw
        try:
            header = read_header(handle, path, known_size)
        except (OSError, EOFError, zlib.error) as exc:
            self.close()
            raise UsageError(f"cannot read {path} as blf: {exc}") from None
        except UsageError:
            self.close()
            raise
        # A file shorter than its header says was cut off, even at an object's end (the
        # header is written when the writer closes the file; 0 when it never did).
        self._claimed_size = header.file_size if known_size is not None else 0
        self._containers = Containers(handle, header.size)
        self._stream = ObjectStream(header.start_time)
        self.frames = 0
        self.skipped: Counter[str] = Counter()  # objects that carry no CAN frame, by kind

    def __iter__(self) -> Iterator[InputItem]:
        """Frames and diagnostics one by one (frames read as columns come as CanFrames)."""
        return one_by_one(self.batches(BLOCK))

    def batches(self, size: int) -> Iterator[list[InputItem]]:
        """The items of each block of log data (in lists of at most ``size`` frames)."""
        stream = self._stream
        waiting = 0
        items: list[InputItem] = []
        try:
            for piece in self._containers.pieces():
                if isinstance(piece, Skipped):  # after the objects of the data before it
                    items += self._items([*stream.read(), piece])
                    continue
                stream.feed(piece)
                waiting += len(piece)
                if waiting >= BLOCK:
                    waiting = 0
                    items += self._items(stream.read())
                    self.position_bytes = _tell(self._raw)
                    yield from by_frames(items, size)
                    items = []
        except (OSError, EOFError, zlib.error) as exc:  # a damaged gzip stream around it
            items.append(self._damage(f"reading stopped: {exc}"))
        items += self._items(stream.read(final=True))
        items += self._ends()
        self.position_bytes = self.size_bytes or _tell(self._raw)
        if items:
            yield from by_frames(items, size)

    def _items(self, records: list[CanFrame | FrameColumns | Skipped]) -> list[InputItem]:
        out: list[InputItem] = []
        repeats = 0  # the same damage again, right after the last
        for index, record in enumerate(records):
            if isinstance(record, Skipped) and record.damage is not None:
                following = records[index + 1] if index + 1 < len(records) else None
                if isinstance(following, Skipped) and following.damage == record.damage:
                    repeats += 1
                    continue
                times = f" ({repeats + 1:,} times in a row)" if repeats else ""
                out.append(self._damage(f"after frame {self.frames:,}: {record.damage}{times}"))
                repeats = 0
                continue
            if isinstance(record, FrameColumns):
                if self.first_time is None:
                    self.first_time = float(record.time[0])
                self.last_time = float(record.time[-1])
                self.frames += len(record)
                out.append(record)
            elif isinstance(record, CanFrame):
                problem = time_problem(record.time)
                if problem:
                    out.append(self._damage(f"frame {self.frames + 1} skipped: its {problem}"))
                    continue
                if self.first_time is None:
                    self.first_time = record.time
                self.last_time = record.time
                self.frames += 1
                out.append(record)
            else:
                self.skipped[record.kind] += 1
        return out

    def _ends(self) -> list[Event]:
        """What the end of the file says: a cut, no frame at all, objects skipped."""
        out: list[Event] = []
        cut = self._containers.cut_at
        if cut is not None and not self._stream.cut:
            out.append(self._cut(f" at byte {cut:,}"))
        elif self._stream.cut:
            out.append(self._cut("" if cut is None else f" at byte {cut:,}"))
        elif self.size_bytes is not None and self._claimed_size > self.size_bytes:
            out.append(
                self._damage(
                    f"the BLF file is cut off at byte {self.size_bytes:,} of the "
                    f"{self._claimed_size:,} its header gives (as a copy that did not finish "
                    f"leaves it): the {self.frames:,} frames before the cut were read"
                )
            )
        if not self.frames and self.size_bytes:
            out.append(
                self._damage(
                    f"no CAN frame could be read from {self.size_bytes:,} bytes read as "
                    "BLF; check the file's format (--format)"
                )
            )
        if self.skipped:
            kinds = ", ".join(f"{n:,} {kind}" for kind, n in self.skipped.most_common())
            self.notes.append(f"objects that carry no CAN frame were skipped: {kinds}")
        return out

    def _cut(self, where: str) -> Event:
        return self._damage(
            f"the BLF file is cut off inside an object{where} (as a logger that lost power "
            f"leaves it): the {self.frames:,} frames before the cut were read"
        )

    def _damage(self, detail: str) -> Event:
        return diagnostic(
            self.last_time or 0.0, self.source, BAD_FRAME, detail, frames_read=self.frames
        )

    @property
    def stats(self) -> dict[str, int]:
        stats = {"frames": self.frames}
        if self.skipped:
            stats["objects_skipped"] = sum(self.skipped.values())
        return stats


def _tell(handle: IO[bytes]) -> int:
    try:
        return handle.tell()
    except (OSError, ValueError):
        return 0
