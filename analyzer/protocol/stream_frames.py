"""Events of one framed TCP / UART message: a control command, a forwarded CAN frame or feedback."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from analyzer.protocol.codec import decode_command
from analyzer.protocol.feedback import decode_feedback
from analyzer.protocol.framing import RawFrame
from analyzer.protocol.ids import FRAME_CAN, FRAME_CONTROL, TCP_MARKER
from analyzer.protocol.types import TOPIC_COMMAND, CanFrame, Event, hexstr

# Decodes a CAN frame with extra fields (the decoder's general CAN path, with its state).
CanPath = Callable[[CanFrame, str, dict[str, Any]], list[Event]]


def stream_frame_events(
    frame: RawFrame, source: str, extra: dict[str, Any], can: CanPath
) -> list[Event]:
    """The events of ``frame`` (CRC already checked by the framer); ``extra`` fields (the
    direction) go into each; a forwarded CAN frame is decoded by ``can``."""
    data = frame.data
    warnings: list[str] = []
    if frame.frame_type in (FRAME_CONTROL, FRAME_CAN) and data[12:14] != TCP_MARKER:
        warnings.append(f"bytes 12-13 are {hexstr(data[12:14])}, expected 40 88")
    if frame.frame_type == FRAME_CONTROL:
        if any(data[3:12]):
            warnings.append("reserved bytes 3-11 are not zero: " + hexstr(data[3:12]))
        fields, more = decode_command(data[14:22])
        fields.update(extra)
        fields["transport"] = "stream"
        return [Event(TOPIC_COMMAND, frame.time, source, fields, warnings + more)]
    if frame.frame_type == FRAME_CAN:
        can_id = int.from_bytes(data[3:7], "big")
        if any(data[7:12]):
            warnings.append("reserved bytes 7-11 are not zero: " + hexstr(data[7:12]))
        inner = CanFrame(frame.time, can_id, data[14:22], channel=source)
        events = can(inner, source, {**extra, "transport": "stream", "crc_set": frame.crc_set})
        for event in events:
            event.warnings[:0] = warnings
        return events
    layout, fields, more = decode_feedback(data)
    assert layout is not None  # the framer only passes feedback of a known length byte
    fields["raw"] = hexstr(data)
    fields.update(extra)
    fields["transport"] = "stream"
    return [Event(layout.topic, frame.time, source, fields, warnings + more)]
