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


# python-can interfaces whose error frames are SocketCAN's: error classes in the ID, the
# details in 8 data bytes as linux/can/error.h lays them out.
SOCKETCAN_ERROR_INTERFACES = frozenset({"socketcan", "socketcand", "gs_usb", "virtual"})


def frame_from_message(
    msg: MessageLike, channel: str | None = None, *, socketcan_errors: bool = True
) -> CanFrame:
    """A ``can.Message`` -> CanFrame (remote frames carry no data but keep their DLC).

    ``channel`` names the channel when the message does not (a live bus). An error frame
    of an adapter that encodes errors its own way (``socketcan_errors`` false: PCAN,
    Kvaser, Vector, ...) gets error class 0, an unspecified error; its bytes are kept.
    """
    if channel is None:
        channel = msg.channel
    foreign_error = msg.is_error_frame and not socketcan_errors
    return CanFrame(
        float(msg.timestamp or 0.0),
        0 if foreign_error else int(msg.arbitration_id),
        b"" if msg.is_remote_frame else bytes(msg.data or b""),
        bool(msg.is_extended_id),
        "" if channel is None else str(channel),
        bool(msg.is_remote_frame),
        bool(msg.is_error_frame),
        bool(msg.is_fd),
        "rx" if msg.is_rx else "tx",
        int(msg.dlc or 0) if msg.is_remote_frame else 0,
    )
