"""The log data of a BLF file (what its containers hold, one after the other) read as it comes.

``ObjectStream`` is fed the bytes of the containers in order and gives the objects whole
in them, in order: runs of CAN data frames as columns (``columns``), every other
object one at a time (``objects``). It never stands still and never grows without bound:

- the next object is looked for where the last one ends and up to 4 bytes later (the
  padding python-can writes); anything else up to the next ``LOBJ`` is skipped, and said;
- an object whose header is damaged (a size smaller than its header, a size of 0 that
  would read the same object for ever, a header version Vector does not document) is
  said and skipped up to the next ``LOBJ``;
- an object claiming more than ``MAX_OBJECT`` bytes is damage too: the stream keeps at
  most that much while it waits for the rest of an object; so is a CAN object longer
  than its kind can be (read as it says, it would swallow the objects after it);
- at the end, an object the data ends inside is said (the file was cut off).
"""

from __future__ import annotations

from analyzer.inputs.blf.columns import Chain, chain, message_columns
from analyzer.inputs.blf.layout import BASE_HEADER, OBJECT_SIGNATURE
from analyzer.inputs.blf.objects import Skipped, header_problem, read_object, size_problem
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.types import CanFrame

MAX_OBJECT = 16 << 20  # no object of a CAN log is near this (containers hold 128 KiB)
_WINDOW = 8  # python-can looks for the next signature in this many bytes
_LEAST_WINDOW, _MOST_WINDOW = 1 << 12, 1 << 22

Record = CanFrame | FrameColumns | Skipped


class ObjectStream:
    """See the module docstring. ``start_time``: the file header's measurement start."""

    def __init__(self, start_time: float) -> None:
        self.start_time = start_time
        self._pieces: list[bytes] = []
        self.cut = False  # the data ended inside an object
        self._gap = 0  # bytes skipped since the last object, not said yet
        self._gap_why = ""
        # Bytes looked at for a run of objects at once: it grows while runs fill it and
        # shrinks when they break early, so damage costs no scan of the whole data.
        self._window = _LEAST_WINDOW

    def feed(self, data: bytes) -> None:
        if data:
            self._pieces.append(data)

    def read(self, *, final: bool = False) -> list[Record]:
        """Every object whole in what was fed (all of it at the ``final`` call)."""
        data = b"".join(self._pieces)
        self._pieces.clear()
        out: list[Record] = []
        pos = 0
        while pos < len(data):
            step = self._step(data, pos, final, out)
            if step is None:
                break
            assert step > pos  # every step moves on: no object is read twice
            pos = step
        if pos < len(data):
            self._pieces.append(data[pos:])
        if final:
            self._say_gap(out)
        return out

    def _step(self, data: bytes, pos: int, final: bool, out: list[Record]) -> int | None:
        """Read on from ``pos``: the new position, or None to wait for more data."""
        size = len(data)
        at = data.find(OBJECT_SIGNATURE, pos, pos + _WINDOW)
        if at < 0:
            if not final and size < pos + _WINDOW:
                return None  # the next object may start in the bytes still to come
            return self._skip(data, pos, final, out, "no BLF object starts there")
        if size - at < BASE_HEADER.size + 16:
            return self._end(data, at, final, out)
        self._say_gap(out)
        limit = min(size, at + self._window)
        found = chain(data, at, limit)
        if found is not None and found.end - at > self._window // 2:
            self._window = min(_MOST_WINDOW, 2 * self._window)
        else:
            self._window = max(_LEAST_WINDOW, self._window // 4)
        if found is not None:
            self._columns(data, found, out)
            return found.end
        _, header_size, version, length, kind = BASE_HEADER.unpack_from(data, at)
        problem = header_problem(header_size, version, length) or size_problem(
            kind, header_size, length
        )
        if problem is None and length > MAX_OBJECT:
            problem = f"a size of {length:,} bytes, more than any object of a CAN log"
        if problem is not None:  # skipped with what follows it up to the next object
            self._gap += 4
            return self._skip(data, at + 4, final, out, f"an object of type {kind} with {problem}")
        if at + length > size:
            return self._end(data, at, final, out)
        out.append(read_object(data, at, self.start_time))
        return at + length

    def _skip(self, data: bytes, pos: int, final: bool, out: list[Record], why: str) -> int:
        """Skip to the next signature from ``pos`` (said once found, or at the end)."""
        self._gap_why = self._gap_why or why
        at = data.find(OBJECT_SIGNATURE, pos)
        if at >= 0:
            self._gap += at - pos
            self._say_gap(out)
            return at
        end = len(data)
        if final:
            if self._gap or any(data[pos:]):  # zeros after the last object: padding
                self._gap += end - pos
        else:  # keep the last bytes: the next ones may complete a signature
            end = max(pos + 1, end - (len(OBJECT_SIGNATURE) - 1))
            self._gap += end - pos
        return end

    def _say_gap(self, out: list[Record]) -> None:
        if self._gap:
            out.append(Skipped("bytes", f"{self._gap:,} bytes skipped: {self._gap_why}"))
        self._gap, self._gap_why = 0, ""

    def _end(self, data: bytes, at: int, final: bool, out: list[Record]) -> int | None:
        """An object not whole yet: wait for the rest; at the end, say it was cut."""
        if not final:
            return None
        self._say_gap(out)
        self.cut = True  # the reader says so, with the frames read before
        return len(data)

    def _columns(self, data: bytes, found: Chain, out: list[Record]) -> None:
        """The chained objects in order: CAN data frames as columns, the rest one by one."""
        usable, frames = message_columns(data, found, self.start_time)
        others = (~usable).nonzero()[0].tolist()
        done = 0  # rows of ``frames`` handed on
        first = 0  # the first object not handed on
        for index in others:
            if index > first:
                count = index - first
                out.append(frames.take(slice(done, done + count)))
                done += count
            out.append(read_object(data, int(found.starts[index]), self.start_time))
            first = index + 1
        if done < len(frames):
            out.append(frames.take(slice(done, len(frames))) if done else frames)
