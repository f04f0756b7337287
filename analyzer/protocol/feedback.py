"""Gimbal feedback messages of chapter 2.2: attitude (0x0C) and laser ranging (0x10)."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from analyzer.protocol.compiled import Code
from analyzer.protocol.crc import crc_bytes
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import (
    FEEDBACK_MESSAGE_SIZE,
    FRAME_ATTITUDE,
    FRAME_RANGING,
    HEADER,
)
from analyzer.protocol.layout import Layout
from analyzer.protocol.types import TOPIC_GIMBAL_ATTITUDE, TOPIC_GIMBAL_RANGING

GIMBAL_TYPES = {
    1: "35x zoom 2MP / 30x zoom 4K",
    2: "30x zoom 5MP",
    3: "3.5x zoom",
    4: "3.5x zoom dual-sensor",
    5: "laser distance measurement",
    7: "30x zoom dual-sensor",
}
CONTROL_MODES = {1: "full_lock", 2: "course_following", 3: "locking"}
WIDE_MOTOR_YAW_TYPES = frozenset({3, 4})  # 3.5x zoom models: motor yaw up to +-325 deg
MOTOR_YAW_LIMIT = 17000  # centidegrees: +-170 deg
WIDE_MOTOR_YAW_LIMIT = 32500  # centidegrees: +-325 deg on WIDE_MOTOR_YAW_TYPES

# Bytes 12-15 of every feedback message: CMD+DID 0x21 0xFE, C_ID 0x0F, Data_id 0x01.
FEEDBACK_ID_BYTES = b"\x21\xfe\x0f\x01"
MessageDecoder = Callable[[bytes], tuple[dict[str, Any], list[str]]]


@dataclass(frozen=True)
class FeedbackLayout:
    """One feedback message kind, selected by the length byte at offset 2."""

    length_byte: int
    name: str
    topic: str
    layout: Layout  # fields at their offsets within the 32-byte message
    crc_offset: int  # the CRC covers bytes 0 .. crc_offset-1

    @property
    def frame_size(self) -> int:
        """Bytes up to and including the CRC (the rest up to 32 is zero padding)."""
        return self.crc_offset + 2


ATTITUDE = FeedbackLayout(
    FRAME_ATTITUDE,
    "attitude",
    TOPIC_GIMBAL_ATTITUDE,
    Layout(
        (
            Field(
                "gimbal_type",
                16,
                "u8",
                labels=GIMBAL_TYPES,
                default=1,
                description="gimbal type (Note 1)",
            ),
            Field(
                "tracking",
                17,
                "u8",
                boolean=True,
                default=False,
                description="trace_flag: target tracking is on",
            ),
            Field(
                "control_mode",
                18,
                "u8",
                labels=CONTROL_MODES,
                default=3,
                description="control mode (Note 2)",
            ),
            Field(
                "pitch_deg",
                19,
                "s16",
                div=100,
                unit="deg",
                minimum=-11000,
                maximum=6000,
                description="pitch angle theta",
            ),
            Field(
                "yaw_deg",
                21,
                "u16",
                div=100,
                unit="deg",
                minimum=0,
                maximum=36000,
                description="yaw angle psi (geomagnetic)",
            ),
            Field(
                "motor_yaw_deg",
                23,
                "s16",
                div=100,
                unit="deg",
                minimum=-WIDE_MOTOR_YAW_LIMIT,
                maximum=WIDE_MOTOR_YAW_LIMIT,
                description="yaw motor angle; +-170 deg, +-325 deg on 3.5x zoom models",
            ),
        ),
        FEEDBACK_MESSAGE_SIZE,
    ),
    crc_offset=25,
)

RANGING = FeedbackLayout(
    FRAME_RANGING,
    "ranging",
    TOPIC_GIMBAL_RANGING,
    Layout(
        (
            Field(
                "success",
                16,
                "u8",
                boolean=True,
                default=True,
                description="distance measuring success marker",
            ),
            Field("distance_m", 17, "u16", div=10, unit="m", description="target distance"),
            Field("height_m", 19, "s16", div=10, unit="m", description="target height"),
            Field(
                "longitude_deg",
                21,
                "s32",
                div=10_000_000,
                unit="deg",
                minimum=-1_800_000_000,
                maximum=1_800_000_000,
                description="target longitude",
            ),
            Field(
                "latitude_deg",
                25,
                "s32",
                div=10_000_000,
                unit="deg",
                minimum=-900_000_000,
                maximum=900_000_000,
                description="target latitude",
            ),
        ),
        FEEDBACK_MESSAGE_SIZE,
    ),
    crc_offset=29,
)

LAYOUTS: dict[int, FeedbackLayout] = {ATTITUDE.length_byte: ATTITUDE, RANGING.length_byte: RANGING}
FRAME_SIZES: dict[int, int] = {k: v.frame_size for k, v in LAYOUTS.items()}


@functools.cache
def message_decoder(length_byte: int) -> MessageDecoder:
    """A 32-byte message of the layout of ``length_byte`` -> (fields, warnings) in one
    generated function, with the checks of ``decode_feedback_fields`` in the same order
    (made on first use)."""
    layout = LAYOUTS[length_byte]
    code = Code()
    code.lines.append("    warnings = []")
    fields = layout.layout.fields
    raws = code.unpack(fields)
    for f, r in zip(fields, raws, strict=True):
        code.field(f, r)
    zeros9, ids = code.constant(bytes(9)), code.constant(FEEDBACK_ID_BYTES)
    padding = code.constant(bytes(FEEDBACK_MESSAGE_SIZE - layout.frame_size))
    note = code.constant(_note)
    code.lines += [
        f"    if data[3:12] != {zeros9}:",
        f"        warnings.append({note}(data, 3, 12, 'reserved'))",
        f"    if data[12:16] != {ids}:",
        f"        warnings.append({note}(data, 12, 16, 'id'))",
        f"    if data[{layout.frame_size}:] != {padding}:",
        f"        warnings.append({note}(data, {layout.frame_size}, 32, 'padding'))",
    ]
    if layout.length_byte == FRAME_ATTITUDE:
        names = [f.name for f in fields]
        kind, motor = raws[names.index("gimbal_type")], raws[names.index("motor_yaw_deg")]
        wide = code.constant(WIDE_MOTOR_YAW_TYPES)
        code.lines += [
            f"    if ({motor} > {MOTOR_YAW_LIMIT} or {motor} < -{MOTOR_YAW_LIMIT})"
            f" and {kind} not in {wide}:",
            f"        warnings.append({code.constant(_motor_note)}({motor}))",
        ]
    decode: MessageDecoder = code.define(
        "decode(data)", [*code.lines, f"    return {code.result()}, warnings"]
    )
    return decode


def _note(data: bytes, start: int, end: int, what: str) -> str:
    """The warning about bytes ``start``..``end`` of a message that are not as they should."""
    text = data[start:end].hex(" ").upper()
    if what == "reserved":
        return "reserved bytes 3-11 are not zero: " + text
    if what == "id":
        return "bytes 12-15 are " + text + ", expected 21 FE 0F 01"
    return "padding after the CRC is not zero: " + text


def _motor_note(raw_motor: int) -> str:
    return (
        f"motor_yaw_deg: {raw_motor / 100:.2f} deg out of range [-170.00, 170.00] deg "
        "for this gimbal type"
    )


def decode_feedback(message: bytes) -> tuple[FeedbackLayout | None, dict[str, Any], list[str]]:
    """A CRC-checked feedback message (27 / 31 bytes, padding optional) -> fields.

    Returns a new dict and list on every call (callers add fields of their own). The usual
    message (32 bytes) goes through its layout's generated decoder, any other through
    ``decode_feedback_fields``, with the same result."""
    if len(message) == FEEDBACK_MESSAGE_SIZE and message[2] in LAYOUTS:
        fields, warnings = message_decoder(message[2])(message)
        return LAYOUTS[message[2]], fields, warnings
    return decode_feedback_fields(message)


def decode_feedback_fields(
    message: bytes,
) -> tuple[FeedbackLayout | None, dict[str, Any], list[str]]:
    """``decode_feedback`` the long way: any message, field by field."""
    warnings: list[str] = []
    layout = LAYOUTS.get(message[2]) if len(message) >= 3 else None
    if layout is None or len(message) < layout.frame_size:
        return None, {}, ["not a feedback message"]
    data = bytes(message[:FEEDBACK_MESSAGE_SIZE]).ljust(FEEDBACK_MESSAGE_SIZE, b"\0")
    fields = layout.layout.decode(data, warnings)
    if any(data[3:12]):
        warnings.append(_note(data, 3, 12, "reserved"))
    if data[12:16] != FEEDBACK_ID_BYTES:
        warnings.append(_note(data, 12, 16, "id"))
    padding = bytes(message[layout.frame_size : FEEDBACK_MESSAGE_SIZE])
    if any(padding):
        warnings.append(_note(padding, 0, len(padding), "padding"))
    if layout is ATTITUDE:
        raw_motor = ATTITUDE.layout.fields[5].read_raw(data)
        if (
            abs(raw_motor) > MOTOR_YAW_LIMIT
            and fields["gimbal_type_code"] not in WIDE_MOTOR_YAW_TYPES
        ):
            warnings.append(_motor_note(raw_motor))
    return layout, fields, warnings


def encode_feedback(layout: FeedbackLayout, *, check_range: bool = True, **values: Any) -> bytes:
    """Values -> a complete 32-byte feedback message with header, CRC and padding."""
    buffer = layout.layout.encode(values, check_range=check_range)
    buffer[0:2] = HEADER
    buffer[2] = layout.length_byte
    buffer[12:16] = FEEDBACK_ID_BYTES
    buffer[layout.crc_offset : layout.crc_offset + 2] = crc_bytes(buffer[: layout.crc_offset])
    return bytes(buffer)


def encode_attitude(
    *,
    pitch_deg: float,
    yaw_deg: float,
    motor_yaw_deg: float = 0.0,
    gimbal_type: int = 1,
    tracking: bool = False,
    control_mode: int = 3,
    check_range: bool = True,
) -> bytes:
    """A 32-byte attitude feedback message (send as four 8-byte CAN frames)."""
    return encode_feedback(
        ATTITUDE,
        check_range=check_range,
        pitch_deg=pitch_deg,
        yaw_deg=yaw_deg,
        motor_yaw_deg=motor_yaw_deg,
        gimbal_type=gimbal_type,
        tracking=tracking,
        control_mode=control_mode,
    )


def encode_ranging(
    *,
    distance_m: float,
    height_m: float,
    latitude_deg: float,
    longitude_deg: float,
    success: bool = True,
    check_range: bool = True,
) -> bytes:
    """A 32-byte laser-ranging feedback message."""
    return encode_feedback(
        RANGING,
        check_range=check_range,
        distance_m=distance_m,
        height_m=height_m,
        latitude_deg=latitude_deg,
        longitude_deg=longitude_deg,
        success=success,
    )


def segments(message: bytes, size: int = 8) -> list[bytes]:
    """Split a feedback message into the CAN frames that carry it."""
    return [message[i : i + size] for i in range(0, len(message), size)]
