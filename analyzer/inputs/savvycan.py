"""SavvyCAN / GVRET native CSV: ``Time Stamp,ID,Extended,Dir,Bus,LEN,D1..D8``, line by line.

The layout is SavvyCAN's FrameFileIO::saveNativeCSVFile: the time in microseconds
(since 1970 when SavvyCAN used the system clock, else since the capture started),
the ID in hex, ``true`` / ``false`` for an extended ID, ``Rx`` / ``Tx``, the bus
number, the length and eight data columns (unused ones ``00``), each followed by a
comma. The older layout without ``Dir`` is read too. A line that is not a frame is a
``bad_line`` diagnostic with its number; reading goes on with the next line.
"""

from __future__ import annotations

from collections.abc import Iterator

from analyzer.inputs.base import ABSOLUTE, RELATIVE_TO_START, InputItem, InputReader, time_problem
from analyzer.inputs.python_can.text_logs import RAW_LIMIT, text_lines
from analyzer.inputs.textlines import damage_after_line
from analyzer.protocol.types import BAD_LINE, CanFrame, Event, diagnostic

ABSOLUTE_FROM_US = 10**15  # a microsecond count this large is a date (after 2001)
MAX_DATA = 64  # a CAN FD frame written with more data columns than the header names


class SavvyCanReader(InputReader):
    """Frames of a SavvyCAN native CSV; the channel is ``bus<N>`` from the Bus column."""

    format_name = "savvycan"

    def __init__(self, path: str) -> None:
        super().__init__(path)
        self._raw = self._open_binary()
        self._damage: list[str] = []
        self._lines = text_lines(self._raw, self._damage)
        self.frames = 0
        self.bad_lines = 0
        self.lines = 0
        self._has_dir = True

    def __iter__(self) -> Iterator[InputItem]:
        for number, line in enumerate(self._lines, start=1):
            self.lines = number
            text = line.strip()
            if number == 1 and text.lower().startswith("time stamp"):
                self._has_dir = ",dir," in text.lower()
                continue
            if self._damage:
                yield from self._reported_damage()
            if not text:
                continue
            item = self._frame(text, number)
            if isinstance(item, CanFrame):
                self.frames += 1
                if self.first_time is None:
                    self.first_time = item.time
                    if item.time < ABSOLUTE_FROM_US / 1e6:
                        self.time_base = RELATIVE_TO_START
                    else:
                        self.time_base = ABSOLUTE
                self.last_time = item.time
                if not self.frames & 0xFF:
                    self.position_bytes = self._raw.tell()
            else:
                self.bad_lines += 1
            yield item
        yield from self._reported_damage()
        self.position_bytes = self.size_bytes or 0

    def _frame(self, text: str, number: int) -> CanFrame | Event:
        fields = [f.strip() for f in text.split(",")]
        first_data = 6 if self._has_dir else 5
        try:
            micros = int(fields[0])
            can_id = int(fields[1], 16)
            extended = fields[2].lower() in ("true", "1")
            if fields[2].lower() not in ("true", "false", "1", "0"):
                raise ValueError(f"Extended is {fields[2]!r}, not true or false")
            direction = fields[3].lower() if self._has_dir else "rx"
            if direction not in ("rx", "tx"):
                raise ValueError(f"Dir is {fields[3]!r}, not Rx or Tx")
            bus = int(fields[first_data - 2])
            length = int(fields[first_data - 1])
            if not 0 <= length <= MAX_DATA:
                raise ValueError(f"length {length}")
            cells = fields[first_data : first_data + length]
            if len(cells) < length:
                raise ValueError(f"{len(cells)} data bytes for a length of {length}")
            data = bytes(int(cell, 16) for cell in cells)
            if can_id > (0x1FFFFFFF if extended else 0x7FF):
                raise ValueError(f"ID 0x{can_id:X} too large")
            problem = time_problem(micros / 1e6)
            if problem:
                raise ValueError(problem)
        except (ValueError, IndexError) as exc:
            shown = text if len(text) <= 60 else text[:57] + "..."
            return diagnostic(
                self.last_time or 0.0,
                self.source,
                BAD_LINE,
                f"line {number}: not a SavvyCAN frame ({exc}): {shown!r}",
                text[:RAW_LIMIT].encode("utf-8", "replace"),
                line=number,
            )
        return CanFrame(
            micros / 1e6, can_id, data, extended, f"bus{bus}", False, False, length > 8, direction
        )

    def _reported_damage(self) -> Iterator[Event]:
        for problem in self._damage:
            yield damage_after_line(self.source, self.last_time or 0.0, self.lines, problem)
        self._damage.clear()

    @property
    def stats(self) -> dict[str, int]:
        return {"lines": self.lines, "frames": self.frames, "bad_lines": self.bad_lines}
