"""Plain CAN frames read in a row as arrays: times, IDs, lengths, payloads (the columnar path).

A reader that reads a block of a log at once (candump text, BLF records) hands its
well-formed classic data frames on as one ``FrameColumns``: no CanFrame is built for a
frame nobody keeps, and the decoder takes the arrays as they are
(``analyzer.protocol.vector_decode``). Remote, error and CAN FD frames, and anything
the reader had to look at line by line, come as CanFrames and diagnostics between
such blocks, in file order. This module imports no numpy: the arrays are made by the
readers, which import it only when they read.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from analyzer.protocol.types import CanFrame

if TYPE_CHECKING:
    import numpy.typing as npt

    Array = npt.NDArray[Any]
else:
    Array = Any

DIRECTIONS: tuple[str, ...] = ("", "rx", "tx")  # ``direction`` holds an index into this


@dataclass(slots=True)
class FrameColumns:
    """Classic data frames as columns, in file order.

    ``time`` float64 seconds; ``can_id`` int64; ``extended`` bool; ``length`` the data
    length (0..8); ``data`` an (n, 8) uint8 array, zero after ``length``; ``channel``
    an index into ``channels`` (the channel names); ``direction`` an index into
    ``DIRECTIONS``.
    """

    time: Array
    can_id: Array
    extended: Array
    length: Array
    data: Array
    channel: Array
    channels: list[str]
    direction: Array

    def __len__(self) -> int:
        return int(self.time.shape[0])

    def frame(self, row: int) -> CanFrame:
        """Row ``row`` as the CanFrame a line-by-line reader makes of it."""
        size = int(self.length[row])
        return CanFrame(
            float(self.time[row]),
            int(self.can_id[row]),
            self.data[row, :size].tobytes(),
            bool(self.extended[row]),
            self.channels[int(self.channel[row])],
            False,
            False,
            False,
            DIRECTIONS[int(self.direction[row])],
        )

    def frames(self) -> list[CanFrame]:
        """Every row as a CanFrame (for sinks that keep raw frames)."""
        times = self.time.tolist()
        ids = self.can_id.tolist()
        extended = self.extended.tolist()
        lengths = self.length.tolist()
        rows = self.data.tobytes()
        channels = self.channels
        names = [channels[c] for c in self.channel.tolist()]
        directions = [DIRECTIONS[d] for d in self.direction.tolist()]
        return [
            CanFrame(
                times[i],
                ids[i],
                rows[8 * i : 8 * i + lengths[i]],
                extended[i],
                names[i],
                False,
                False,
                False,
                directions[i],
            )
            for i in range(len(times))
        ]

    def take(self, rows: Array | slice) -> FrameColumns:
        """The frames at ``rows`` (a slice, index array or mask), as columns."""
        return FrameColumns(
            self.time[rows],
            self.can_id[rows],
            self.extended[rows],
            self.length[rows],
            self.data[rows],
            self.channel[rows],
            self.channels,
            self.direction[rows],
        )


def empty_columns(np_: Any) -> FrameColumns:
    """No frames (``np_`` is the numpy module)."""
    return FrameColumns(
        np_.zeros(0, np_.float64),
        np_.zeros(0, np_.int64),
        np_.zeros(0, bool),
        np_.zeros(0, np_.uint8),
        np_.zeros((0, 8), np_.uint8),
        np_.zeros(0, np_.int32),
        [],
        np_.zeros(0, np_.int8),
    )
