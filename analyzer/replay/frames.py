"""A flight's frames of the ground station's, to send again: commands and UAV status, checked.

Only what a ground station sends is replayed: the commands (``/gimbal/command``, both
components) and the UAV status (``/uav/gps``, ``/uav/altitude``, ``/uav/attitude``,
``/uav/text``). The gimbal's own feedback is never sent. Each frame keeps the bytes the
flight carried; one whose values the codec would not encode (a value outside the
document's range, an unknown command or label) is refused, with the codec's reason.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from analyzer.protocol.codec import EncodeError, encode_command
from analyzer.protocol.command_table import BY_CODE
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    GPS_ID,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.types import (
    TOPIC_COMMAND,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    TOPIC_UAV_TEXT,
    Event,
)
from analyzer.protocol.uav import STATUS_FRAMES
from analyzer.render import describe_event

STATUS_IDS = {
    TOPIC_UAV_GPS: GPS_ID,
    TOPIC_UAV_ALTITUDE: ALTITUDE_ID,
    TOPIC_UAV_ATTITUDE: UAV_ATTITUDE_ID,
}
SENT_TOPICS = frozenset({TOPIC_COMMAND, *STATUS_IDS, TOPIC_UAV_TEXT})
CAN_DATA = 8


@dataclass(frozen=True, slots=True)
class Outgoing:
    """One frame to send: when the flight sent it (its time, Unix s), on which CAN ID, its
    data, the event it belongs to in words, and why it is refused ('' when it is sent)."""

    time: float
    can_id: int
    data: bytes
    topic: str
    what: str
    refused: str = ""

    @property
    def is_command(self) -> bool:
        return self.can_id == CONTROL_ID


def outgoing(event: Event) -> list[Outgoing]:
    """The frames of ``event`` a ground station sent (none for anything else)."""
    topic = event.topic
    if topic not in SENT_TOPICS:
        return []
    data = _raw(event.fields)
    what = describe_event(event)
    if topic == TOPIC_COMMAND:
        why = command_refusal(data, event.fields)
        return [Outgoing(event.time, CONTROL_ID, data, topic, what, why)]
    if topic == TOPIC_UAV_TEXT:
        return _text_frames(event, data, what)
    can_id = STATUS_IDS[topic]
    return [Outgoing(event.time, can_id, data, topic, what, _status_refusal(can_id, event.fields))]


def _raw(fields: dict[str, Any]) -> bytes:
    try:
        return bytes.fromhex(str(fields.get("raw", "")))
    except ValueError:
        return b""


def command_refusal(data: bytes, fields: dict[str, Any]) -> str:
    """Why a command's bytes must not be sent ('' when they may): not 8 bytes, a command
    the document does not have, or a value the codec refuses to encode (out of range,
    an unknown label): the decoded values are encoded again, with the range checked."""
    if len(data) != CAN_DATA:
        return f"{len(data)} data bytes, a command has {CAN_DATA}"
    row = BY_CODE.get((data[0], data[1]))
    if row is None:
        return f"not a command of the document (S_ID 0x{data[0]:02X}, CMD 0x{data[1]:02X})"
    table = [row.selector, *row.all_fields()] if row.selector is not None else row.all_fields()
    params = {f.name: fields[f.name] for f in table if f is not None and f.name in fields}
    try:
        encode_command(row.name, s_id=row.s_id, **params)
    except EncodeError as exc:
        return str(exc)
    return ""


def _status_refusal(can_id: int, fields: dict[str, Any]) -> str:
    """A UAV status frame whose values the codec will not encode (a latitude beyond 90)."""
    layout = STATUS_FRAMES[can_id].layout
    try:
        layout.encode({f.name: fields[f.name] for f in layout.fields if f.name in fields})
    except EncodeError as exc:
        return f"{STATUS_FRAMES[can_id].name}: {exc}"
    return ""


def _text_frames(event: Event, data: bytes, what: str) -> list[Outgoing]:
    """A text message as the frames it came in (8 bytes each, the last on its end ID),
    spread evenly from its first frame's time to its last's."""
    chunks = [data[i : i + CAN_DATA] for i in range(0, len(data), CAN_DATA)] or [bytes(CAN_DATA)]
    start = event.fields.get("start_time")
    first = float(start) if isinstance(start, (int, float)) else event.time
    step = (event.time - first) / (len(chunks) - 1) if len(chunks) > 1 else 0.0
    return [
        Outgoing(
            first + n * step,
            TEXT_END_ID if n == len(chunks) - 1 else TEXT_ID,
            chunk,
            TOPIC_UAV_TEXT,
            what if n == 0 else f"text (frame {n + 1} of {len(chunks)})",
        )
        for n, chunk in enumerate(chunks)
    ]
