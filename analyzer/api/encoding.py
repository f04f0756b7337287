"""``encode`` and ``tcp_frame``: a command by name and values in physical units, as bytes."""

from __future__ import annotations

from typing import Any

from analyzer.protocol.codec import encode_command, find_command
from analyzer.protocol.framing import wrap_control

__all__ = ["encode", "tcp_frame"]

ParamValue = float | str  # a number in the parameter's unit, or one of its labels
_CODEC_OPTIONS = frozenset({"s_id", "check_range", "require_all"})


def encode(name: str, component: str = "gimbal", **params: ParamValue) -> bytes:
    """The 8 CAN data bytes (S_ID, CMD, DATA1..6) of the command ``name``.

    ``params`` are named and in the units of the decoded events (``COMMANDS`` lists
    them): ``pan_speed_dps=-5``, ``yaw_deg=45``, ``axis="pitch"``, ``mode="single"``.
    A parameter with a default may be left out. ``component="dual_sensor"`` picks the
    dual-sensor camera's commands (S_ID 0x1F). An unknown command or parameter, a
    missing parameter or a value outside the document's range raises ``ValueError``
    naming it, the value and the range (or the valid choices).

    >>> from analyzer import encode
    >>> encode("gimbal_control", pan_speed_dps=-5).hex(" ")
    '0f 04 0c fe 00 00 00 00'
    >>> encode("specified_angle", yaw_deg=45).hex(" ")
    '0f 08 01 c2 01 00 00 00'
    >>> encode("palette", component="dual_sensor", palette="iron_red").hex(" ")
    '1f 02 02 00 00 00 00 00'
    >>> encode("gimbal_control", pan_speed_dps=150)
    Traceback (most recent call last):
    ...
    ValueError: gimbal_control: pan_speed_dps: 150 out of range [-100.00, 100.00] deg/s
    """
    values: dict[str, Any] = dict(params)
    try:
        options = sorted(values.keys() & _CODEC_OPTIONS)  # the codec's, no parameters
        if options:
            valid = sorted(f.name for f in find_command(name, component).all_fields())
            raise ValueError(
                f"unknown parameter(s) {', '.join(options)}; valid: {', '.join(valid)}"
            )
        return encode_command(name, s_id=component, require_all=True, **values)
    except ValueError as exc:
        text = str(exc)
        named = text.startswith(name) or text.startswith("unknown command")
        raise ValueError(text if named else f"{name}: {text}") from None


def tcp_frame(name: str, component: str = "gimbal", **params: ParamValue) -> bytes:
    """The 24-byte TCP / UART control frame of chapter 3 for a command: ``EB 90 0A``,
    nine zero bytes, ``40 88``, the 8 bytes of ``encode(name, component, **params)`` and
    the CRC-16 (low byte first). Raises ``ValueError`` as ``encode`` does.

    >>> from analyzer import tcp_frame
    >>> tcp_frame("look_down").hex(" ").upper()
    'EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5E'
    """
    return wrap_control(encode(name, component, **params))
