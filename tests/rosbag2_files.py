"""ROS bags of CAN frames made the way ros2_socketcan + rosbag2 (and ROS 1 rosbag) make them.

rosbag2's MCAP storage plugin (ros2/rosbag2, rosbag2_storage_mcap/src/mcap_storage.cpp)
writes with the C++ mcap library: profile ``ros2``, no compression, no chunk CRC (its
defaults), summary with CRC; one schema per message type, named like
``can_msgs/msg/Frame``, encoding ``ros2msg``, holding the full definition text with every
dependency after a line of 80 ``=`` and ``MSG: pkg/Type`` (message_definition_cache.cpp);
one channel per topic, message encoding ``cdr``, metadata ``offered_qos_profiles`` (the
YAML list of qos.cpp, version 9 names) and ``topic_type_hash``; log time = receive time,
publish time = send time; at the end a metadata record ``rosbag2`` whose
``serialized_metadata`` is the bag's metadata.yaml. ros2_socketcan's receiver node publishes
``can_msgs/msg/Frame`` on ``from_can_bus`` with ``header.frame_id = "can"``, the stamp taken
when the frame was read, and the ``data`` array of a reused message (bytes past ``dlc`` are
left over from earlier frames).
"""

from __future__ import annotations

import io
import struct
from collections.abc import Sequence
from decimal import Decimal
from pathlib import Path
from typing import Any

from mcap.writer import CompressionType, Writer
from mcap_ros2._dynamic import serialize_dynamic

from analyzer.protocol.types import CanFrame

FRAME_TYPE = "can_msgs/msg/Frame"
SEPARATOR = "=" * 80
FRAME_MSG = """\
std_msgs/Header header
uint32 id
bool is_rtr
bool is_extended
bool is_error
uint8 dlc
uint8[8] data
"""
HEADER_MSG = """\
# Standard metadata for higher-level stamped data types.
# This is generally used to communicate timestamped data
# in a particular coordinate frame.

# Two-integer timestamp that is expressed as seconds and nanoseconds.
builtin_interfaces/Time stamp

# Transform frame with which this data is associated.
string frame_id
"""
TIME_MSG = """\
# This message communicates ROS Time defined here:
# https://design.ros2.org/articles/clock_and_time.html

# The seconds component, valid over all int32 values.
int32 sec

# The nanoseconds component, valid in the range [0, 1e9), to be added to the seconds component.
# e.g. 1.7s = 1s + 700000000ns
uint32 nanosec
"""
# get_full_text(): the root text, then each dependency after its delimiter
FRAME_DEFINITION = (
    f"{FRAME_MSG}\n{SEPARATOR}\nMSG: std_msgs/Header\n{HEADER_MSG}"
    f"\n{SEPARATOR}\nMSG: builtin_interfaces/Time\n{TIME_MSG}"
)
STRING_DEFINITION = "# This was originally provided as an example message.\nstring data\n"

_INFINITE = "    sec: 9223372036\n    nsec: 854775807\n"
# serialize_rclcpp_qos_vector() of the receiver's publisher (depth 500, reliable)
QOS_PROFILES = (
    "- history: keep_last\n  depth: 500\n  reliability: reliable\n  durability: volatile\n"
    f"  deadline:\n{_INFINITE}  lifespan:\n{_INFINITE}  liveliness: automatic\n"
    f"  liveliness_lease_duration:\n{_INFINITE}  avoid_ros_namespace_conventions: false"
)
TYPE_HASH = "RIHS01_" + "5" * 64
RECEIVE_DELAY_NS = 150_000  # the recorder gets a message this long after the driver stamped it


def stamp_ns(seconds: float) -> int:
    """Nanoseconds of a time read from a text log (its shortest decimal form, exactly)."""
    return int(Decimal(repr(seconds)) * 10**9)


def frame_message(frame: CanFrame, previous: bytes, frame_id: str = "can") -> dict[str, Any]:
    """The can_msgs/msg/Frame ros2_socketcan publishes for ``frame``: ``previous`` is the
    data array of the message before (its bytes past dlc stay)."""
    stamp = stamp_ns(frame.time)
    data = frame.data + previous[len(frame.data) :]
    return {
        "header": {
            "stamp": {"sec": stamp // 10**9, "nanosec": stamp % 10**9},
            "frame_id": frame_id,
        },
        "id": frame.can_id,
        "is_rtr": frame.is_remote,
        "is_extended": frame.extended,
        "is_error": frame.is_error,
        "dlc": frame.dlc,
        "data": data[:8],
    }


def cdr_frames(frames: Sequence[CanFrame]) -> list[tuple[int, bytes]]:
    """(receive time ns, CDR bytes) of each frame, encoded by mcap-ros2-support."""
    encode = serialize_dynamic(FRAME_TYPE, FRAME_DEFINITION)[FRAME_TYPE]
    out = []
    previous = bytes(8)
    for frame in frames:
        message = frame_message(frame, previous)
        previous = message["data"]
        out.append((stamp_ns(frame.time) + RECEIVE_DELAY_NS, bytes(encode(message))))
    return out


FD_FRAME_TYPE = "ros2_socketcan_msgs/msg/FdFrame"
FD_FRAME_MSG = """\
std_msgs/Header header
uint32 id
bool is_extended
bool is_error
uint8 len
uint8[<=64] data
"""
FD_FRAME_DEFINITION = FRAME_DEFINITION.replace(FRAME_MSG, FD_FRAME_MSG)


def cdr_fd_frames(frames: Sequence[CanFrame]) -> list[tuple[int, bytes]]:
    """(receive time ns, CDR bytes) of ros2_socketcan's FdFrame for each frame (CAN FD
    enabled: published on from_can_bus_fd, data resized to the frame's length)."""
    encode = serialize_dynamic(FD_FRAME_TYPE, FD_FRAME_DEFINITION)[FD_FRAME_TYPE]
    out = []
    for frame in frames:
        stamp = stamp_ns(frame.time)
        message = {
            "header": {
                "stamp": {"sec": stamp // 10**9, "nanosec": stamp % 10**9},
                "frame_id": "can",
            },
            "id": frame.can_id,
            "is_extended": frame.extended,
            "is_error": frame.is_error,
            "len": len(frame.data),
            "data": frame.data,
        }
        out.append((stamp + RECEIVE_DELAY_NS, bytes(encode(message))))
    return out


def bag_metadata_yaml(topic: str, count: int, start_ns: int, end_ns: int) -> str:
    """The ``serialized_metadata`` rosbag2 stores in its ``rosbag2`` metadata record."""
    qos = QOS_PROFILES.replace("\n", "\n        ")
    return (
        "rosbag2_bagfile_information:\n"
        "  version: 9\n"
        "  storage_identifier: mcap\n"
        "  duration:\n"
        f"    nanoseconds: {end_ns - start_ns}\n"
        "  starting_time:\n"
        f"    nanoseconds_since_epoch: {start_ns}\n"
        f"  message_count: {count}\n"
        "  topics_with_message_count:\n"
        "    - topic_metadata:\n"
        f"        name: {topic}\n"
        f"        type: {FRAME_TYPE}\n"
        "        serialization_format: cdr\n"
        f"        offered_qos_profiles:\n        {qos}\n"
        f"        type_description_hash: {TYPE_HASH}\n"
        f"      message_count: {count}\n"
        '  compression_format: ""\n'
        '  compression_mode: ""\n'
        "  relative_file_paths:\n"
        "    - flight_0.mcap\n"
        "  files:\n"
        "    - path: flight_0.mcap\n"
        "      starting_time:\n"
        f"        nanoseconds_since_epoch: {start_ns}\n"
        "      duration:\n"
        f"        nanoseconds: {end_ns - start_ns}\n"
        f"      message_count: {count}\n"
        "  custom_data: ~\n"
        "  ros_distro: jazzy"
    )


def rosbag2_mcap(
    frames: Sequence[CanFrame],
    *,
    topic: str | None = "/from_can_bus",
    extra_topics: Sequence[str] = (),
    messages: Sequence[tuple[int, bytes]] | None = None,
    finished: bool = True,
    schema: tuple[str, str] = (FRAME_TYPE, FRAME_DEFINITION),
) -> bytes:
    """An MCAP file as ``ros2 bag record -s mcap`` writes it for ros2_socketcan's topic.

    ``topic=None`` leaves the CAN channel out; ``extra_topics`` adds std_msgs/msg/String
    channels (one message each); ``messages`` replaces the encoded frames; ``finished=False`` stops before the summary (a killed
    recorder: chunks written so far, no footer)."""
    records = cdr_frames(frames) if messages is None else list(messages)
    out = io.BytesIO()
    writer = Writer(
        out,
        chunk_size=768 * 1024,
        compression=CompressionType.NONE,
        enable_crcs=True,  # chunk CRCs are cleared below, as noChunkCRC leaves them
    )
    writer.start(profile="ros2", library="libmcap 1.4.1")
    metadata = {"offered_qos_profiles": QOS_PROFILES, "topic_type_hash": TYPE_HASH}
    if topic is not None:
        schema_id = writer.register_schema(schema[0], "ros2msg", schema[1].encode())
        channel_id = writer.register_channel(topic, "cdr", schema_id, metadata)
        for sequence, (log_time, data) in enumerate(records, 1):
            writer.add_message(channel_id, log_time, data, log_time - RECEIVE_DELAY_NS, sequence)
    string_schema = 0
    for extra in extra_topics:
        if not string_schema:
            string_schema = writer.register_schema(
                "std_msgs/msg/String", "ros2msg", STRING_DEFINITION.encode()
            )
        extra_id = writer.register_channel(extra, "cdr", string_schema, metadata)
        text = b"ok\0"
        data = b"\x00\x01\x00\x00" + struct.pack("<I", len(text)) + text
        writer.add_message(extra_id, records[-1][0] if records else 1, data, 1, 1)
    if records and topic is not None:
        start, end = records[0][0], records[-1][0]
        yaml = bag_metadata_yaml(topic, len(records), start, end)
        writer.add_metadata("rosbag2", {"serialized_metadata": yaml})
    if finished:
        writer.finish()
    else:
        writer.flush()  # the chunks written so far; no summary, no footer
    return clear_chunk_crcs(out.getvalue())


def clear_chunk_crcs(data: bytes) -> bytes:
    """The same file with every chunk's uncompressed CRC set to 0 (not computed), as
    rosbag2's writer options (noChunkCRC) leave them. The summary CRC does not cover
    the data section, and this writer writes no data section CRC."""
    out = bytearray(data)
    at = 8
    while at + 9 <= len(out):
        opcode, length = struct.unpack_from("<BQ", out, at)
        if opcode == 0x06:  # chunk: start, end, uncompressed size, uncompressed crc
            struct.pack_into("<I", out, at + 9 + 24, 0)
        if opcode == 0x0F:  # data end: the summary follows
            break
        at += 9 + length
    return bytes(out)


def write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


# ROS 1: ros_canopen's can_msgs/Frame (Header is std_msgs/Header with seq) as its
# socketcan_bridge publishes it on "received_messages": empty frame_id, seq counting up, a
# new message per frame (data past dlc zero); written by rosbags' ROS 1 bag writer.
ROS1_FRAME_MSG = FRAME_MSG.replace("std_msgs/Header", "Header")


def ros1_messages(frames: Sequence[CanFrame]) -> tuple[object, list[tuple[int, bytes]]]:
    """(rosbags typestore with can_msgs/Frame, [(receive time ns, ROS 1 bytes)])."""
    import numpy as np
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(get_types_from_msg(ROS1_FRAME_MSG, FRAME_TYPE))
    frame_type = store.types[FRAME_TYPE]
    header = store.types["std_msgs/msg/Header"]
    time = store.types["builtin_interfaces/msg/Time"]
    out = []
    for seq, frame in enumerate(frames):
        stamp = stamp_ns(frame.time)
        message = frame_type(
            header=header(seq=seq, stamp=time(stamp // 10**9, stamp % 10**9), frame_id=""),
            id=frame.can_id,
            is_rtr=frame.is_remote,
            is_extended=frame.extended,
            is_error=frame.is_error,
            dlc=frame.dlc,
            data=np.frombuffer(frame.data.ljust(8, b"\0"), dtype=np.uint8),
        )
        out.append((stamp + RECEIVE_DELAY_NS, bytes(store.serialize_ros1(message, FRAME_TYPE))))
    return store, out


def ros1_bag(path: Path, frames: Sequence[CanFrame], topic: str = "/received_messages") -> Path:
    from rosbags.rosbag1 import Writer as Ros1Writer

    store, messages = ros1_messages(frames)
    with Ros1Writer(path) as writer:
        connection = writer.add_connection(topic, FRAME_TYPE, typestore=store)  # type: ignore[arg-type]
        for log_time, data in messages:
            writer.write(connection, log_time, data)
    return path


def ros1_mcap(frames: Sequence[CanFrame], topic: str = "/received_messages") -> bytes:
    """A ROS 1 bag as ``mcap convert`` makes an MCAP of it (foxglove/mcap go/ros/bag2mcap.go):
    profile ros1, zstd chunks of 4 MiB with CRCs, schema named by the bag's type
    (can_msgs/Frame) holding its message definition, message encoding ros1, md5sum as
    channel metadata, log and publish time the bag record's time, bytes unchanged."""
    store, messages = ros1_messages(frames)
    definition, md5sum = store.generate_msgdef(FRAME_TYPE)  # type: ignore[attr-defined]
    out = io.BytesIO()
    writer = Writer(out, chunk_size=4 * 1024 * 1024, compression=CompressionType.ZSTD)
    writer.start(profile="ros1", library="golang-mcap-v0")
    schema = writer.register_schema("can_msgs/Frame", "ros1msg", definition.encode())
    metadata = {"md5sum": md5sum}
    channel = writer.register_channel(topic, "ros1", schema, metadata)
    for sequence, (log_time, data) in enumerate(messages):
        writer.add_message(channel, log_time, data, log_time, sequence)
    writer.finish()
    return out.getvalue()
