"""UAV status frames of chapter 2.3: GPS, altitude, attitude, and reassembled text messages."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from analyzer.protocol.compiled import compile_frame_decoder
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import ALTITUDE_ID, GPS_ID, TEXT_END_ID, TEXT_ID, UAV_ATTITUDE_ID
from analyzer.protocol.layout import Layout
from analyzer.protocol.types import (
    TEXT_UNTERMINATED,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    TOPIC_UAV_TEXT,
    Event,
    diagnostic,
    hexstr,
)


@dataclass(frozen=True)
class StatusFrame:
    """One UAV status CAN frame: its ID, topic and fields."""

    can_id: int
    name: str
    topic: str
    layout: Layout
    description: str


def _deg7(name: str, offset: int, limit: int, what: str) -> Field:
    return Field(
        name,
        offset,
        "s32",
        div=10_000_000,
        unit="deg",
        minimum=-limit * 10_000_000,
        maximum=limit * 10_000_000,
        description=what,
    )


def _angle(name: str, offset: int, what: str) -> Field:
    return Field(name, offset, "s16", div=100, unit="deg", description=what)


STATUS_FRAMES: dict[int, StatusFrame] = {
    s.can_id: s
    for s in (
        StatusFrame(
            GPS_ID,
            "gps",
            TOPIC_UAV_GPS,
            Layout(
                (
                    _deg7("latitude_deg", 0, 90, "latitude"),
                    _deg7("longitude_deg", 4, 180, "fusion longitude"),
                ),
                8,
            ),
            "UAV GPS position",
        ),
        StatusFrame(
            ALTITUDE_ID,
            "altitude",
            TOPIC_UAV_ALTITUDE,
            Layout((Field("altitude_m", 0, "s32", div=100, unit="m", description="altitude"),), 8),
            "UAV flight altitude",
        ),
        StatusFrame(
            UAV_ATTITUDE_ID,
            "attitude",
            TOPIC_UAV_ATTITUDE,
            Layout(
                (
                    _angle("pitch_deg", 0, "pitch angle"),
                    _angle("roll_deg", 2, "roll angle"),
                    _angle("yaw_deg", 4, "yaw angle"),
                ),
                8,
            ),
            "UAV attitude angles",
        ),
    )
}
USED_BYTES = {cid: max(f.end for f in s.layout.fields) for cid, s in STATUS_FRAMES.items()}
StatusDecoder = Callable[[bytes], tuple[dict[str, Any], list[str]]]


@functools.cache
def eight_byte_decoder(can_id: int) -> StatusDecoder:
    """Fields and warnings of 8 data bytes, in one compiled function (the usual frame of
    each ID), made on first use."""
    layout = STATUS_FRAMES[can_id].layout
    used = USED_BYTES[can_id]

    def unused_not_zero(data: bytes, warnings: list[str]) -> None:
        warnings.append(f"unused bytes {used}-7 are not zero: {data[used:].hex(' ').upper()}")

    return compile_frame_decoder(layout.fields, used, 8, unused_not_zero)


def decode_status(can_id: int, data: bytes) -> tuple[dict[str, Any], list[str]]:
    """Data of a GPS / altitude / attitude frame -> fields, warnings. Never raises."""
    if len(data) == 8:  # the usual case
        return eight_byte_decoder(can_id)(data)
    return _decode_odd_status(STATUS_FRAMES[can_id], can_id, data)


def _decode_odd_status(
    status: StatusFrame, can_id: int, data: bytes
) -> tuple[dict[str, Any], list[str]]:
    warnings: list[str] = []
    if len(data) != 8:
        warnings.append(f"{status.name} frame: {len(data)} data bytes, expected 8")
    used = USED_BYTES[can_id]
    if len(data) < used:
        data = bytes(data) + bytes(used - len(data))
    fields = status.layout.decode(bytes(data[:8]).ljust(8, b"\0"), warnings)
    if any(data[used:8]):
        warnings.append(
            f"unused bytes {used}-7 are not zero: {bytes(data[used:8]).hex(' ').upper()}"
        )
    return fields, warnings


def encode_gps(latitude_deg: float, longitude_deg: float) -> bytes:
    return bytes(
        STATUS_FRAMES[GPS_ID].layout.encode(
            {"latitude_deg": latitude_deg, "longitude_deg": longitude_deg}
        )
    )


def encode_altitude(altitude_m: float) -> bytes:
    return bytes(STATUS_FRAMES[ALTITUDE_ID].layout.encode({"altitude_m": altitude_m}))


def encode_uav_attitude(pitch_deg: float, roll_deg: float, yaw_deg: float) -> bytes:
    return bytes(
        STATUS_FRAMES[UAV_ATTITUDE_ID].layout.encode(
            {"pitch_deg": pitch_deg, "roll_deg": roll_deg, "yaw_deg": yaw_deg}
        )
    )


def encode_text(text: str) -> list[tuple[int, bytes]]:
    """ASCII text -> CAN frames: 0x02008201 for all but the last 8 bytes, 0x02008202 last."""
    data = text.encode("ascii")
    chunks = [data[i : i + 8].ljust(8, b"\0") for i in range(0, len(data), 8)] or [bytes(8)]
    return [(TEXT_ID, c) for c in chunks[:-1]] + [(TEXT_END_ID, chunks[-1])]


class TextAssembler:
    """Joins 0x02008201 frames until 0x02008202; reports text that never ends."""

    def __init__(self, source: str, max_bytes: int = 256, stale_after: float = 10.0) -> None:
        self.source = source
        self.max_bytes = max_bytes
        self.stale_after = stale_after
        self._buffer = bytearray()
        self._frames = 0
        self._start = 0.0
        self._last = 0.0

    def feed(self, can_id: int, data: bytes, time: float) -> list[Event]:
        out: list[Event] = []
        if self._frames and time - self._last > self.stale_after:
            out.extend(self._unterminated(time, f"no frame for {time - self._last:.1f} s"))
        if not self._frames:
            self._start = time
        self._buffer += data
        self._frames += 1
        self._last = time
        if can_id == TEXT_END_ID:
            out.append(self._finish(time))
        elif len(self._buffer) > self.max_bytes:
            out.extend(
                self._unterminated(time, f"longer than {self.max_bytes} bytes with no end frame")
            )
        return out

    def tick(self, now: float) -> list[Event]:
        if self._frames and now - self._last > self.stale_after:
            return self._unterminated(now, f"no frame for {now - self._last:.1f} s")
        return []

    def close(self, now: float) -> list[Event]:
        if self._frames:
            return self._unterminated(now, "input ended before the end frame")
        return []

    def _unterminated(self, time: float, why: str) -> list[Event]:
        raw = bytes(self._buffer)
        preview = raw.replace(b"\0", b"").decode("ascii", "backslashreplace")
        event = diagnostic(
            time,
            self.source,
            TEXT_UNTERMINATED,
            f"text message of {self._frames} frame(s) never ended ({why}): {preview!r}",
            raw,
        )
        self._reset()
        return [event]

    def _finish(self, time: float) -> Event:
        raw = bytes(self._buffer)
        warnings: list[str] = []
        body = raw.replace(b"\0", b"")
        text = body.decode("ascii", "backslashreplace")
        if any(b >= 0x80 or (b < 0x20 and b not in (9, 10, 13)) for b in body):
            warnings.append("text contains non-printable or non-ASCII bytes")
        event = Event(
            TOPIC_UAV_TEXT,
            time,
            self.source,
            {"text": text, "frames": self._frames, "start_time": self._start, "raw": hexstr(raw)},
            warnings,
        )
        self._reset()
        return event

    def _reset(self) -> None:
        self._buffer.clear()
        self._frames = 0
