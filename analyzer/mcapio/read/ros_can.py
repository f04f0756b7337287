"""CAN frames as ROS drivers publish them (``can_msgs/msg/Frame``): recognised and decoded.

A ROS 2 bag stores each message in CDR (the DDS wire format), a ROS 1 bag in the ROS 1
serialisation; the message is the same in both::

    std_msgs/Header header   # stamp (sec, nanosec) and frame_id
    uint32 id                # without flags: is_extended / is_rtr / is_error say those
    bool is_rtr
    bool is_extended
    bool is_error
    uint8 dlc
    uint8[8] data            # fixed size: bytes past dlc are left over from earlier frames

ros2_socketcan publishes CAN FD frames as ``ros2_socketcan_msgs/msg/FdFrame`` (``id``,
``is_extended``, ``is_error``, ``uint8 len``, ``uint8[<=64] data``), read the same way.

The layouts are walked with precompiled structs (only ``frame_id`` has a variable length).
The frame's time is its header stamp (when the driver read it from the bus); a zero stamp
falls back to the time the bag recorded the message. A message that does not hold a
plausible frame raises ``RosFrameError`` saying why.
"""

from __future__ import annotations

import struct

from analyzer.protocol.types import CanFrame

# Schema names of can_msgs/msg/Frame: ROS 2 (rosbag2, MCAP) and ROS 1 (.bag).
ROS2_CAN_FRAME = "can_msgs/msg/Frame"
ROS1_CAN_FRAME = "can_msgs/Frame"
ROS2_CANFD_FRAME = "ros2_socketcan_msgs/msg/FdFrame"
# Channel roles of such channels in an MCAP file (see analyzer.mcapio.read.stored_message).
ROLE_ROS_CAN = "ros2-can"
ROLE_ROS1_CAN = "ros1-can"
ROLE_ROS_CANFD = "ros2-canfd"
ROS_CAN_ROLES = frozenset({ROLE_ROS_CAN, ROLE_ROS1_CAN, ROLE_ROS_CANFD})

_NS = 1_000_000_000
CAN_SFF_MAX = 0x7FF
CAN_EFF_MAX = 0x1FFFFFFF

# CDR encapsulation (representation identifier, big endian) -> byte order of the body.
_CDR_ORDER = {0x0000: ">", 0x0001: "<", 0x0006: ">", 0x0007: "<"}  # CDR, CDR2 (plain)
_CDR_HEAD = {order: struct.Struct(order + "iII") for order in "<>"}  # sec, nanosec, len
_CDR_FRAME = {order: struct.Struct(order + "I4B8s") for order in "<>"}  # id .. data
# FdFrame: id, is_extended, is_error, len, (padding), length of the data sequence
_CDR_FD = {order: struct.Struct(order + "I3BxI") for order in "<>"}
_ROS1_HEAD = struct.Struct("<IIII")  # seq, secs, nsecs, frame_id length
_ROS1_FRAME = struct.Struct("<I4B8s")
_FRAME_SIZE = _ROS1_FRAME.size  # 16 bytes from id to the end of data


class RosFrameError(ValueError):
    """A can_msgs/Frame message that cannot be decoded (the detail says why)."""


def ros_can_role(schema_name: str, message_encoding: str) -> str:
    """The role of a channel carrying can_msgs/Frame in an encoding this module reads, else ''."""
    if schema_name == ROS2_CAN_FRAME and message_encoding == "cdr":
        return ROLE_ROS_CAN
    if schema_name == ROS1_CAN_FRAME and message_encoding == "ros1":
        return ROLE_ROS1_CAN
    if schema_name == ROS2_CANFD_FRAME and message_encoding == "cdr":
        return ROLE_ROS_CANFD
    return ""


def ros_frame(role: str, data: bytes, channel: str, log_time_ns: int) -> CanFrame:
    """The frame of a message on a channel of role ``role`` (one of ``ROS_CAN_ROLES``)."""
    if role == ROLE_ROS_CAN:
        return frame_from_cdr(data, channel, log_time_ns)
    if role == ROLE_ROS_CANFD:
        return fd_frame_from_cdr(data, channel, log_time_ns)
    return frame_from_ros1(data, channel, log_time_ns)


def _cdr_body(data: bytes, what: str) -> tuple[str, int, int, int]:
    """(byte order, stamp sec, nanosec, offset of the field after the header) of a CDR
    message that starts with a std_msgs/Header (the offset aligned for a uint32)."""
    if len(data) < 4 + 12:
        raise RosFrameError(f"{len(data)} bytes are too short for a CDR {what}")
    order = _CDR_ORDER.get(int.from_bytes(data[:2], "big"))
    if order is None:
        raise RosFrameError(f"unknown CDR encapsulation 0x{data[0]:02X}{data[1]:02X}")
    sec, nanosec, name_length = _CDR_HEAD[order].unpack_from(data, 4)
    # the body starts after the encapsulation header; uint32 id is aligned to 4 within it
    at = 16 + name_length
    at += -(at - 4) % 4
    if name_length > len(data):
        raise RosFrameError(f"{len(data)} bytes are too short for a CDR {what}")
    return order, sec, nanosec, at


def frame_from_cdr(data: bytes, channel: str, log_time_ns: int) -> CanFrame:
    """A CDR-encoded can_msgs/msg/Frame (with its 4-byte encapsulation header)."""
    order, sec, nanosec, at = _cdr_body(data, ROS2_CAN_FRAME)
    if at + _FRAME_SIZE > len(data):
        raise RosFrameError(f"{len(data)} bytes are too short for a CDR {ROS2_CAN_FRAME}")
    fields = _CDR_FRAME[order].unpack_from(data, at)
    return _frame(sec, nanosec, fields, channel, log_time_ns)


def fd_frame_from_cdr(data: bytes, channel: str, log_time_ns: int) -> CanFrame:
    """A CDR-encoded ros2_socketcan_msgs/msg/FdFrame: a CAN FD frame of up to 64 bytes."""
    order, sec, nanosec, at = _cdr_body(data, ROS2_CANFD_FRAME)
    head = _CDR_FD[order]
    if at + head.size > len(data):
        raise RosFrameError(f"{len(data)} bytes are too short for a CDR {ROS2_CANFD_FRAME}")
    can_id, is_extended, is_error, length, count = head.unpack_from(data, at)
    if count > 64 or length > count:
        raise RosFrameError(f"len {length} with {count} data bytes (at most 64)")
    payload = data[at + head.size : at + head.size + count]
    if len(payload) < count:
        raise RosFrameError(f"{len(data)} bytes are too short for {count} data bytes")
    _check(can_id, 0, is_extended, is_error)
    time = _time(sec, nanosec, log_time_ns)
    return CanFrame(
        time,
        can_id,
        bytes(payload[:length]),
        bool(is_extended),
        channel,
        False,
        bool(is_error),
        True,
    )


def frame_from_ros1(data: bytes, channel: str, log_time_ns: int) -> CanFrame:
    """A ROS 1 serialised can_msgs/Frame (as stored in a .bag file)."""
    if len(data) < _ROS1_HEAD.size:
        raise RosFrameError(f"{len(data)} bytes are too short for a ROS 1 can_msgs/Frame")
    _, secs, nsecs, name_length = _ROS1_HEAD.unpack_from(data)
    at = _ROS1_HEAD.size + name_length
    if at + _FRAME_SIZE > len(data):
        raise RosFrameError(f"{len(data)} bytes are too short for a ROS 1 can_msgs/Frame")
    return _frame(secs, nsecs, _ROS1_FRAME.unpack_from(data, at), channel, log_time_ns)


def _frame(
    sec: int,
    nanosec: int,
    fields: tuple[int, int, int, int, int, bytes],
    channel: str,
    log_time_ns: int,
) -> CanFrame:
    can_id, is_rtr, is_extended, is_error, dlc, data = fields
    _check(can_id, is_rtr, is_extended, is_error)
    if dlc > 8:
        raise RosFrameError(f"dlc {dlc} is over 8")
    time = _time(sec, nanosec, log_time_ns)
    extended, error = bool(is_extended), bool(is_error)
    if is_rtr:
        return CanFrame(time, can_id, b"", extended, channel, True, error, remote_dlc=dlc)
    return CanFrame(time, can_id, data[:dlc], extended, channel, False, error)


def _check(can_id: int, is_rtr: int, is_extended: int, is_error: int) -> None:
    """RosFrameError unless the flags are booleans and the ID fits its kind."""
    if is_rtr > 1 or is_extended > 1 or is_error > 1:
        raise RosFrameError(
            f"flags is_rtr={is_rtr} is_extended={is_extended} is_error={is_error} are not booleans"
        )
    if can_id > (CAN_EFF_MAX if is_extended or is_error else CAN_SFF_MAX):
        kind = "extended" if is_extended else "standard"
        raise RosFrameError(f"id 0x{can_id:X} does not fit a {kind} CAN ID")


def _time(sec: int, nanosec: int, log_time_ns: int) -> float:
    """The header stamp in seconds (the log time when the stamp is zero)."""
    if nanosec >= _NS:
        raise RosFrameError(f"header stamp nanoseconds {nanosec} are over one second")
    # integer true division rounds once, exactly like reading the decimal time of a text log
    stamp = sec * _NS + nanosec
    return (stamp if stamp else log_time_ns) / _NS
