"""ROS 1 ``.bag`` files and rosbag2's sqlite3 ``.db3`` storage, read through ``rosbags``.

Their ``can_msgs/Frame`` topics (ros_canopen's socketcan_bridge in ROS 1, ros2_socketcan in
ROS 2) are read like any CAN capture: each topic becomes the frames' channel, the header
stamp their time (see analyzer.mcapio.read.ros_can). rosbag2's MCAP storage is read by the MCAP
reader (it copes with unfinished and damaged files); this one covers the two storages only
``rosbags`` reads. A bag that ``rosbags`` cannot read is a one-line error; when it fails
part way, the frames before stay and an ``incomplete`` diagnostic says where it stopped.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from analyzer.errors import InputError, NothingReadable, UsageError
from analyzer.inputs.base import InputItem, InputReader, open_binary
from analyzer.mcapio.read.ros_can import (
    ROS2_CAN_FRAME,
    ROS2_CANFD_FRAME,
    RosFrameError,
    fd_frame_from_cdr,
    frame_from_cdr,
    frame_from_ros1,
)
from analyzer.protocol.types import BAD_FRAME, INCOMPLETE, CanFrame, diagnostic

if TYPE_CHECKING:
    pass

Decode = Callable[[bytes, str, int], CanFrame]


class RosbagReader(InputReader):
    """CAN frames of the can_msgs/Frame topics of a ROS 1 bag or a rosbag2 .db3 file (and of
    ros2_socketcan's FdFrame topics in a .db3)."""

    format_name = "rosbag"

    def __init__(self, path: str) -> None:
        super().__init__(path)
        open_binary(path).close()  # a missing or unreadable file: one-line UsageError
        self.size_bytes = os.path.getsize(path)
        self.ros1 = not path.lower().endswith(".db3")
        self._reader: Ros1Reader | Ros2Reader
        try:
            if self.ros1:
                from rosbags.rosbag1 import Reader as Ros1Reader

                self._reader = Ros1Reader(Path(path))
            else:
                from rosbags.rosbag2 import Reader as Ros2Reader

                self._reader = Ros2Reader(Path(path))
            self._reader.open()
        except ImportError as exc:
            missing = f"ROS bag support is not available ({exc}; pip install '.[ros]')"
            raise UsageError(f"cannot read {path}: {missing}") from None
        except Exception as exc:  # rosbags' ReaderError and what a bad header raises
            hint = ""
            if self.ros1 and "index" in str(exc).lower():
                hint = "; an unfinished bag has no index: `rosbag reindex` rebuilds it"
            raise InputError(f"{path}: not a readable ROS bag ({_why(exc)}){hint}") from None
        self._closers.append(self._reader)
        connections = list(self._reader.connections)
        # rosbags names ROS 1 types the ROS 2 way (can_msgs/msg/Frame)
        wanted = {ROS2_CAN_FRAME} if self.ros1 else {ROS2_CAN_FRAME, ROS2_CANFD_FRAME}
        self._wanted = [c for c in connections if c.msgtype in wanted]
        if not self._wanted:
            kinds = sorted({f"{c.topic}  {c.msgtype}" for c in connections})
            raise NothingReadable(
                f"{path}: no can_msgs/Frame topic to read; its {len(kinds)} topic(s):",
                tuple(kinds),
            )
        self.frames = 0
        self.bad_messages = 0

    def __iter__(self) -> Iterator[InputItem]:
        decoders: dict[str, Decode] = {
            ROS2_CAN_FRAME: frame_from_ros1 if self.ros1 else frame_from_cdr,
            ROS2_CANFD_FRAME: fd_frame_from_cdr,
        }
        messages = self._reader.messages(connections=self._wanted)
        last = 0.0  # seconds: the time of the last message read
        try:
            for connection, log_time, data in messages:
                # sqlite3 keeps any type in any column: a damaged .db3 may hold text
                at = _seconds(log_time)
                raw = bytes(data) if isinstance(data, bytes | bytearray | memoryview) else b""
                try:
                    if at is None:
                        raise RosFrameError(f"its time {log_time!r:.40} is no nanoseconds")
                    if not isinstance(data, bytes | bytearray | memoryview):
                        raise RosFrameError(f"its data is {type(data).__name__}, not bytes")
                    last = at
                    decode = decoders[connection.msgtype]
                    frame = decode(raw, connection.topic, log_time)
                except RosFrameError as exc:
                    self.bad_messages += 1
                    yield diagnostic(
                        last,
                        connection.topic,
                        BAD_FRAME,
                        f"{connection.topic}: message not read as a CAN frame: {exc}",
                        raw,
                    )
                    continue
                self.frames += 1
                if self.first_time is None:
                    self.first_time = frame.time
                self.last_time = frame.time
                yield frame
        except Exception as exc:  # a damaged bag: keep what was read, say where it stopped
            yield diagnostic(
                last,
                self.source,
                INCOMPLETE,
                f"the bag cannot be read further ({_why(exc)}); {self.frames} frames read",
            )
        self.position_bytes = self.size_bytes or 0

    @property
    def stats(self) -> dict[str, int]:
        return {"frames": self.frames, "bad_messages": self.bad_messages}


def _seconds(log_time: object) -> float | None:
    """A message's time in seconds (None: not a count of nanoseconds a float holds)."""
    if not isinstance(log_time, int) or isinstance(log_time, bool):
        return None
    try:
        return log_time / 1e9
    except OverflowError:
        return None


def _why(exc: BaseException) -> str:
    text = str(exc).strip() or "no detail"
    return f"{type(exc).__name__}: {text}"
