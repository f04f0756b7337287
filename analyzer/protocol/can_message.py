"""A python-can ``Message`` (from a bus or a log) as this tool's CanFrame: attributes only."""

from __future__ import annotations

from typing import Any, Protocol

from analyzer.protocol.types import CanFrame


class MessageLike(Protocol):
    """What is read of a ``can.Message`` (the core does not import python-can)."""

    timestamp: float
    arbitration_id: int
    data: Any
    dlc: int
    channel: Any
    is_extended_id: bool
    is_remote_frame: bool
    is_error_frame: bool
    is_fd: bool
    is_rx: bool


def frame_from_message(msg: MessageLike, channel: str | None = None) -> CanFrame:
    """A ``can.Message`` -> CanFrame (remote frames carry no data but keep their DLC).

    ``channel`` names the channel when the message does not (a live bus).
    """
    if channel is None:
        channel = msg.channel
    return CanFrame(
        float(msg.timestamp or 0.0),
        int(msg.arbitration_id),
        b"" if msg.is_remote_frame else bytes(msg.data or b""),
        bool(msg.is_extended_id),
        "" if channel is None else str(channel),
        bool(msg.is_remote_frame),
        bool(msg.is_error_frame),
        bool(msg.is_fd),
        "rx" if msg.is_rx else "tx",
        int(msg.dlc or 0) if msg.is_remote_frame else 0,
    )
