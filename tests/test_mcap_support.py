"""Shared helpers of the MCAP tests: realistic traffic and small recordings."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, encode_ranging
from analyzer.protocol.framing import wrap_can, wrap_control
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.types import FROM_IDU, TO_IDU, CanFrame, Event, StreamChunk
from analyzer.protocol.uav import encode_altitude, encode_gps, encode_text, encode_uav_attitude

T0 = 1_700_000_000.0
# The vendor document's 25-byte "One key to down" example (one zero byte too many).
BAD_TCP_EXAMPLE = bytes.fromhex(
    "EB 90 0A 00 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5E"
)


def feedback_frames(t: float, message: bytes, *, channel: str = "can0") -> list[CanFrame]:
    return [
        CanFrame(t + 0.001 * k, FEEDBACK_ID, message[8 * k : 8 * k + 8], channel=channel)
        for k in range(4)
    ]


def traffic(
    seconds: float = 4.0, *, gap_after: float | None = None, bus_off: bool = False
) -> list[RawItem]:
    """Mixed CAN and TCP traffic: commands, feedback every 0.5 s, UAV status, faults.

    ``gap_after``: the gimbal's feedback (attitude and ranging) stops for 2 s after this
    many seconds. ``bus_off``: at the end the adapter goes bus-off and is restarted.
    """
    items: list[RawItem] = []
    steps = int(seconds / 0.05)
    for i in range(steps):
        t = T0 + i * 0.05
        silent = gap_after is not None and gap_after <= i * 0.05 < gap_after + 2.0
        items.append(
            CanFrame(
                t,
                CONTROL_ID,
                encode_command("gimbal_control", pan_speed_dps=-5.0 + i % 10, tilt_speed_dps=0),
                channel="can0",
            )
        )
        if i % 10 == 0 and not silent:
            att = encode_attitude(pitch_deg=-10.0, yaw_deg=i * 0.5 % 360, motor_yaw_deg=3.0)
            items.extend(feedback_frames(t + 0.01, att))
        if i % 10 == 5 and not silent:
            rng = encode_ranging(
                distance_m=120.5, height_m=30.0, latitude_deg=31.12, longitude_deg=118.12
            )
            items.extend(feedback_frames(t + 0.01, rng))
        if i % 4 == 0:
            items.append(
                CanFrame(t + 0.02, GPS_ID, encode_gps(31.1234567, 118.1234567), channel="can0")
            )
            items.append(CanFrame(t + 0.021, ALTITUDE_ID, encode_altitude(506.78), channel="can0"))
            items.append(
                CanFrame(t + 0.022, UAV_ATTITUDE_ID, encode_uav_attitude(1, -2, 90), channel="can0")
            )
        if i % 7 == 3:
            items.append(CanFrame(t + 0.03, 0x123, bytes([i % 256, 1, 2]), False, "can0"))
    # Faults: a feedback message with a broken CRC, a text message, TCP frames.
    broken = bytearray(encode_attitude(pitch_deg=1.0, yaw_deg=2.0, motor_yaw_deg=3.0))
    broken[20] ^= 0xFF
    end = T0 + seconds
    items.extend(feedback_frames(end, bytes(broken)))
    for k, (can_id, data) in enumerate(encode_text("battery low, return home")):
        items.append(CanFrame(end + 0.01 + 0.001 * k, can_id, data, channel="can0"))
    items.append(
        StreamChunk(
            end + 0.1,
            wrap_control(encode_command("look_down")) + BAD_TCP_EXAMPLE,
            source="tcp:127.0.0.1:2000",
            direction=TO_IDU,
        )
    )
    items.append(
        StreamChunk(
            end + 0.2,
            wrap_can(GPS_ID, encode_gps(31.0, 118.0)),
            source="tcp:127.0.0.1:2000",
            direction=FROM_IDU,
        )
    )
    if bus_off:  # SocketCAN error frames: bus-off, then restarted
        items.append(CanFrame(end + 0.3, 0x040, bytes(8), channel="can0", is_error=True))
        items.append(CanFrame(end + 0.4, 0x100, bytes(8), channel="can0", is_error=True))
    items.sort(key=lambda item: item.time)
    return items


def decode_all(items: list[RawItem], *, emit_other: bool = False) -> list[Event]:
    decoder = ProtocolDecoder(emit_other=emit_other)
    events: list[Event] = []
    for item in items:
        events.extend(decoder.feed(item))
    events.extend(decoder.close())
    return events


def batches(items: list[RawItem], *, emit_other: bool = False, size: int = 25) -> list[Batch]:
    """Decode like the capture engine does and cut into batches."""
    decoder = ProtocolDecoder(emit_other=emit_other)
    out: list[Batch] = []
    for start in range(0, len(items), size):
        chunk = items[start : start + size]
        events: list[Event] = []
        for item in chunk:
            events.extend(decoder.feed(item))
        out.append(Batch(list(chunk), events))
    out.append(Batch([], decoder.close()))
    return out


def write_recording(
    path: Path, items: list[RawItem] | None = None, *, emit_other: bool = False, **kwargs: Any
) -> list[Batch]:
    from analyzer.mcapio.write.sink import McapSink

    kwargs.setdefault("flush_interval", None)
    sink = McapSink(path, metadata={"source": "test:traffic"}, **kwargs)
    parts = batches(traffic() if items is None else items, emit_other=emit_other)
    for batch in parts:
        sink.handle(batch)
    sink.close()
    return parts


def event_dicts(events: list[Event]) -> list[dict[str, Any]]:
    """As they come out of JSON (tuples become lists etc.)."""
    return [json.loads(json.dumps(e.to_dict())) for e in events]
