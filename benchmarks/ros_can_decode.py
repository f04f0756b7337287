"""Decoding ROS 2 can_msgs/msg/Frame (CDR): the fixed-layout struct walk against mcap-ros2-support.

Encodes mixed gimbal traffic (the frames of the convert benchmark: commands, feedback, UAV
status, foreign IDs; every frame different) as ros2_socketcan publishes it, with
mcap-ros2-support's CDR encoder, then times, in the same run and best of ``--repeat``:

- per message: ``analyzer.mcapio.read.ros_can.frame_from_cdr`` against mcap-ros2-support's
  decoder (``mcap_ros2.decoder.DecoderFactory``) plus building the same
  CanFrame from the decoded fields;
- whole file: a rosbag2-style MCAP read by ``Recording.items()`` against
  ``mcap_ros2.reader.read_ros2_messages`` (mcap's reader plus the dynamic decoder).

Both sides must give the same frames; the ratios say how much faster the struct walk is.

  python benchmarks/ros_can_decode.py [--frames 200000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from mcap.records import Schema
from mcap.writer import CompressionType, Writer
from mcap_ros2._dynamic import serialize_dynamic
from mcap_ros2.decoder import DecoderFactory

from analyzer.mcapio.read.reader import McapRecording
from analyzer.mcapio.read.ros_can import ROS2_CAN_FRAME, frame_from_cdr
from analyzer.protocol.types import CanFrame
from benchmarks.convert_speed import make_frames

DEFINITION = (
    "std_msgs/Header header\nuint32 id\nbool is_rtr\nbool is_extended\nbool is_error\n"
    "uint8 dlc\nuint8[8] data\n\n" + "=" * 80 + "\nMSG: std_msgs/Header\n"
    "builtin_interfaces/Time stamp\nstring frame_id\n\n" + "=" * 80 + "\n"
    "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
)
TOPIC = "/from_can_bus"


def encode(frames: Sequence[CanFrame]) -> list[tuple[int, bytes]]:
    encoder = serialize_dynamic(ROS2_CAN_FRAME, DEFINITION)[ROS2_CAN_FRAME]
    out = []
    for frame in frames:
        stamp = round(frame.time * 1e9)
        message = {
            "header": {
                "stamp": {"sec": stamp // 10**9, "nanosec": stamp % 10**9},
                "frame_id": "can",
            },
            "id": frame.can_id,
            "is_rtr": False,
            "is_extended": frame.extended,
            "is_error": False,
            "dlc": len(frame.data),
            "data": frame.data.ljust(8, b"\0"),
        }
        out.append((stamp, bytes(encoder(message))))
    return out


def from_library(message: Any, log_time: int) -> CanFrame:
    """The CanFrame of a message decoded by mcap-ros2-support (same rules as ours)."""
    stamp = message.header.stamp.sec * 10**9 + message.header.stamp.nanosec
    data = bytes(message.data)[: message.dlc]
    return CanFrame((stamp or log_time) / 10**9, message.id, data, message.is_extended, TOPIC)


def best(run: Callable[[], list[CanFrame]], repeat: int) -> tuple[float, list[CanFrame]]:
    times, result = [], []
    for _ in range(repeat):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return min(times), result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)

    frames = [f for f in make_frames(args.frames) if not f.is_remote][: args.frames]
    messages = encode(frames)
    schema = Schema(id=1, name=ROS2_CAN_FRAME, encoding="ros2msg", data=DEFINITION.encode())
    decode = DecoderFactory().decoder_for("cdr", schema)
    assert decode is not None
    n = len(messages)

    ours_t, ours = best(lambda: [frame_from_cdr(d, TOPIC, t) for t, d in messages], args.repeat)
    lib_t, lib = best(lambda: [from_library(decode(d), t) for t, d in messages], args.repeat)
    assert ours == lib, "the two decoders disagree"
    print(f"per message  {n} frames")
    print(f"  struct walk          {n / ours_t:>12,.0f} frames/s")
    print(f"  mcap-ros2-support    {n / lib_t:>12,.0f} frames/s")
    print(f"  ratio                {lib_t / ours_t:>12.1f} x faster")

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bag.mcap"
        with path.open("wb") as f:
            writer = Writer(f, chunk_size=768 * 1024, compression=CompressionType.NONE)
            writer.start(profile="ros2", library="libmcap 1.4.1")
            schema = writer.register_schema(ROS2_CAN_FRAME, "ros2msg", DEFINITION.encode())
            channel = writer.register_channel(TOPIC, "cdr", schema)
            for sequence, (log_time, data) in enumerate(messages, 1):
                writer.add_message(channel, log_time, data, log_time, sequence)
            writer.finish()

        from mcap_ros2.reader import read_ros2_messages

        def library_file() -> list[CanFrame]:
            return [from_library(m.ros_msg, m.log_time_ns) for m in read_ros2_messages(str(path))]

        file_ours_t, file_ours = best(lambda: list(McapRecording(path).items()), args.repeat)  # type: ignore[arg-type]
        file_lib_t, file_lib = best(library_file, args.repeat)
        assert file_ours == file_lib == ours, "the two file readers disagree"
    print(f"whole file   {n} frames, uncompressed rosbag2-style MCAP")
    print(f"  Recording.items()    {n / file_ours_t:>12,.0f} frames/s")
    print(f"  read_ros2_messages   {n / file_lib_t:>12,.0f} frames/s")
    print(f"  ratio                {file_lib_t / file_ours_t:>12.1f} x faster")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
