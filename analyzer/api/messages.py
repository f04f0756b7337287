"""python-can messages: a command for the gimbal, and the UAV status frames of chapter 2.3."""

from __future__ import annotations

from typing import TYPE_CHECKING

from analyzer.api.encoding import ParamValue, encode
from analyzer.protocol.ids import CONTROL_ID
from analyzer.protocol.uav import STATUS_FRAMES, encode_text

if TYPE_CHECKING:
    import can

__all__ = ["STATUS_NAMES", "can_message", "status_message", "text_messages"]

# status_message's names -> the CAN ID of the frame (gps, altitude, attitude), and text.
STATUS_IDS: dict[str, int] = {status.name: can_id for can_id, status in STATUS_FRAMES.items()}
STATUS_NAMES: tuple[str, ...] = (*STATUS_IDS, "text")
TEXT_FRAME_BYTES = 8


def can_message(name: str, component: str = "gimbal", **params: ParamValue) -> can.Message:
    """The command as a ``can.Message`` for ``bus.send``: extended ID 0x00000F01, the 8
    bytes of ``encode(name, component, **params)``. Raises ``ValueError`` as ``encode``.

    >>> from analyzer import can_message
    >>> msg = can_message("gimbal_control", tilt_speed_dps=5)
    >>> hex(msg.arbitration_id), msg.is_extended_id, msg.data.hex(" ")
    ('0xf01', True, '0f 04 00 00 f4 01 00 00')
    """
    return _message(CONTROL_ID, encode(name, component, **params))


def status_message(name: str, **values: float | str) -> can.Message:
    """A UAV status frame (chapter 2.3) as a ``can.Message``, for whoever plays the
    aircraft: ``"gps"`` (``latitude_deg``, ``longitude_deg``), ``"altitude"``
    (``altitude_m``), ``"attitude"`` (``pitch_deg``, ``roll_deg``, ``yaw_deg``), or
    ``"text"`` (``text``: at most 8 ASCII characters, one end frame; ``text_messages``
    sends any length). Every value must be given; an unknown name, a missing or unknown
    value or one outside the frame's range raises ``ValueError`` naming it.

    >>> from analyzer import status_message
    >>> gps = status_message("gps", latitude_deg=31.1234567, longitude_deg=118.1234567)
    >>> hex(gps.arbitration_id), gps.data.hex(" ")
    ('0xff15', '07 10 8d 12 87 35 68 46')
    >>> status_message("altitude", altitude_m=506.78).data.hex(" ")
    'f6 c5 00 00 00 00 00 00'
    >>> status_message("gps", latitude_deg=95, longitude_deg=0)
    Traceback (most recent call last):
    ...
    ValueError: gps: latitude_deg: 95 out of range [-90.0000000, 90.0000000] deg
    """
    if name == "text":
        text = values.pop("text", None)
        _no_others(name, values, "text")
        if not isinstance(text, str):
            raise ValueError("text: missing parameter text (a str of ASCII characters)")
        frames = text_messages(text)
        if len(frames) > 1:
            raise ValueError(
                f"text: {text!r} needs {len(frames)} frames of {TEXT_FRAME_BYTES} bytes; "
                "text_messages(text) gives them all"
            )
        return frames[0]
    can_id = STATUS_IDS.get(name)
    if can_id is None:
        raise ValueError(f"unknown status message {name!r}; valid: {', '.join(STATUS_NAMES)}")
    layout = STATUS_FRAMES[can_id].layout
    names = [f.name for f in layout.fields]
    _no_others(name, {k: v for k, v in values.items() if k not in names}, *names)
    for field in layout.fields:
        if field.name not in values:
            raise ValueError(f"{name}: missing parameter {field.name} ({field.accepts()})")
    try:
        data = bytes(layout.encode(values))
    except ValueError as exc:
        raise ValueError(f"{name}: {exc}") from None
    return _message(can_id, data)


def text_messages(text: str) -> list[can.Message]:
    """An ASCII text message (chapter 2.3.4) as CAN frames of 8 bytes: 0x02008201 for
    each but the last, 0x02008202 for the last (zero-padded). Raises ``ValueError`` for
    characters outside ASCII.

    >>> from analyzer import text_messages
    >>> [(hex(m.arbitration_id), bytes(m.data)) for m in text_messages("UAV armed")]
    [('0x2008201', b'UAV arme'), ('0x2008202', b'd\\x00\\x00\\x00\\x00\\x00\\x00\\x00')]
    """
    try:
        frames = encode_text(text)
    except UnicodeEncodeError as exc:
        bad = text[exc.start : exc.end]
        raise ValueError(f"text: {bad!r} is not ASCII (the text message carries ASCII)") from None
    return [_message(can_id, data) for can_id, data in frames]


def _no_others(name: str, others: dict[str, float | str], *valid: str) -> None:
    if others:
        raise ValueError(
            f"{name}: unknown parameter(s) {', '.join(sorted(others))}; valid: {', '.join(valid)}"
        )


def _message(can_id: int, data: bytes) -> can.Message:
    import can

    return can.Message(arbitration_id=can_id, data=data, is_extended_id=True, is_rx=False)
