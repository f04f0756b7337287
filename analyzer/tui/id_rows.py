"""The bus sniffer table's rows: one per CAN ID or stream, each remembering which bytes changed."""

from __future__ import annotations

import math

from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.types import FROM_IDU, TO_IDU, CanFrame, StreamChunk
from analyzer.tui.rates import Meter

HIGHLIGHT_S = 1.0  # a changed data byte stays highlighted this long
MAX_ROWS = 2048  # distinct IDs with a row of their own; the rest share one row
OVERFLOW_KEY = "more IDs"

ID_LABELS: dict[int, str] = {
    CONTROL_ID: "control",
    FEEDBACK_ID: "feedback",
    GPS_ID: "uav gps",
    ALTITUDE_ID: "uav alt",
    UAV_ATTITUDE_ID: "uav att",
    TEXT_ID: "uav text",
    TEXT_END_ID: "text end",
}

_ARROWS = {TO_IDU: "→idu", FROM_IDU: "←idu"}


def frame_bits(frame: CanFrame) -> int:
    """Bits a classic CAN frame occupies on the wire (without stuff bits), interframe included."""
    return (67 if frame.extended else 47) + 8 * len(frame.data)


def stream_key(chunk: StreamChunk) -> str:
    """The row key of a stream chunk: its source and direction."""
    return f"{chunk.source} {_ARROWS.get(chunk.direction, chunk.direction)}".strip()


class IdRow:
    """One line of the bus sniffer table: a CAN ID (or a stream source + direction)."""

    __slots__ = (
        "can_id",
        "changed_at",
        "count",
        "data",
        "extended",
        "key",
        "label",
        "last_time",
        "meter",
        "protocol",
    )

    def __init__(self, key: str, can_id: int | None, label: str, protocol: bool) -> None:
        self.key = key
        self.can_id = can_id
        self.label = label
        self.protocol = protocol
        self.extended = True
        self.count = 0
        self.meter = Meter()  # frames per second, from their times
        self.last_time = 0.0
        self.data = b""
        self.changed_at: list[float] = []

    def note_data(self, data: bytes, time: float) -> None:
        """Remember which bytes differ from the previous frame, and when."""
        old = self.data
        changed = self.changed_at
        if len(changed) < len(data):
            # bytes seen for the first time are not "changed"
            changed.extend([-math.inf] * (len(data) - len(changed)))
        for i in range(min(len(old), len(data))):
            if old[i] != data[i]:
                changed[i] = time
        self.data = data

    def changed_mask(self, now: float, within: float = HIGHLIGHT_S) -> tuple[bool, ...]:
        """Per data byte: did it change in the last ``within`` seconds?"""
        if self.count <= 1:
            return (False,) * len(self.data)
        return tuple(now - t < within for t in self.changed_at[: len(self.data)])


def add_row(
    rows: dict[int | str, IdRow], key: int | str, frame: CanFrame | None, max_rows: int
) -> tuple[IdRow, bool]:
    """The row for a key seen for the first time, and whether it was added to ``rows``.

    Past ``max_rows`` every new key shares the overflow row, so a bus full of random IDs
    does not grow the table without bound.
    """
    if len(rows) >= max_rows:
        row = rows.get(OVERFLOW_KEY)
        if row is not None:
            return row, False
        row = rows[OVERFLOW_KEY] = IdRow(OVERFLOW_KEY, None, "other IDs", False)
        return row, True
    if frame is None:
        row = IdRow(str(key), None, "stream", True)
    else:
        label = ID_LABELS.get(frame.can_id, "foreign")
        text = f"0x{frame.can_id:08X}" if frame.extended else f"0x{frame.can_id:03X}"
        row = IdRow(text, frame.can_id, label, frame.can_id in ID_LABELS)
        row.extended = frame.extended
        if frame.can_id in ID_LABELS and not frame.extended:
            row.label += "!"  # a protocol ID sent as a standard frame
    rows[key] = row
    return row, True
