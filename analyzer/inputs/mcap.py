"""MCAP files: this project's recordings (raw frames and chunks) and ROS bags' CAN frames."""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any

from analyzer.errors import NothingReadable, UsageError
from analyzer.inputs.base import InputItem, InputReader, open_binary
from analyzer.mcapio.channels import RAW_TOPICS, ROLE_EVENT, ROLE_RAW
from analyzer.mcapio.read.ros_can import ROS2_CAN_FRAME, ROS_CAN_ROLES
from analyzer.mcapio.read.stored_message import ChannelKind
from analyzer.protocol.types import INCOMPLETE, TOPIC_DIAGNOSTICS, diagnostic


def readable(kind: ChannelKind, *, stored: bool) -> bool:
    """Whether a channel gives something to decode (``stored``: events as recorded)."""
    if stored:
        return kind.ours and kind.role == ROLE_EVENT
    if kind.role in ROS_CAN_ROLES:
        return True
    if kind.role == ROLE_RAW:
        return kind.topic in RAW_TOPICS
    return kind.ours and kind.topic == TOPIC_DIAGNOSTICS


class McapReader(InputReader):
    """Raw items of a recording, for decoding again.

    Besides the raw items, ``read_replay`` gives back the diagnostics a new decode cannot
    re-create (link state, bad lines of the original input). A recording whose writer was
    killed is recovered as far as it can be read; a diagnostic then says
    so at the end. The CAN frames of a ROS bag (``can_msgs/msg/Frame`` channels) are read
    like raw frames, each topic becoming the frame's channel. A file with channels but none
    this tool can read raises ``NothingReadable`` listing them (before reading when the file
    has a summary, else once the read found nothing).
    """

    format_name = "mcap"

    def __init__(self, path: str, *, stored: bool = False) -> None:
        super().__init__(path)
        open_binary(path).close()  # a missing or unreadable file: one-line UsageError
        self.size_bytes = os.path.getsize(path)
        try:
            from analyzer.mcapio.read.reader import read_events, read_replay
        except ImportError as exc:
            raise UsageError(f"cannot read {path}: MCAP support is not available ({exc})") from None
        # stored: the events as recorded (decoded by the version that wrote the file).
        self._items: Any = read_events(path) if stored else read_replay(path)
        self.stored = stored
        self.items = 0
        self._check_readable()

    def _check_readable(self) -> None:
        """NothingReadable when the channels known so far are all of no use here."""
        recording = getattr(self._items, "recording", None)
        kinds = None if recording is None else recording.channel_kinds()
        if not kinds or any(readable(kind, stored=self.stored) for kind in kinds):
            return
        if self.stored:
            why = "--stored reads the events this tool records, and it holds none"
        else:
            why = f"no channel this tool can read (its own recordings, {ROS2_CAN_FRAME} in CDR)"
        raise NothingReadable(
            f"{self.path}: {why}; its {len(kinds)} channel(s):",
            tuple(kind.describe() for kind in kinds),
        )

    def __iter__(self) -> Iterator[InputItem]:
        recording = getattr(self._items, "recording", None)
        read = recording.position if recording is not None else None
        for item in self._items:
            self.items += 1
            if read is not None:
                self.position_bytes = read.bytes  # for the progress line
            if self.first_time is None:
                self.first_time = item.time
            self.last_time = item.time
            yield item
        if not self.items:
            self._check_readable()  # a file read sequentially: its channels are known now
        self.position_bytes = self.size_bytes or 0
        note = getattr(self._items, "note", "")
        if getattr(self._items, "recovered", False) and note:
            yield diagnostic(self.last_time or 0.0, self.source, INCOMPLETE, note)
        # every damaged part already came as an `incomplete` diagnostic where it was
        for damage in getattr(self._items, "damage", ()):
            self.notes.append(f"{self.path}: damaged recording: {damage.detail}")

    @property
    def stats(self) -> dict[str, int]:
        return {"recorded_events" if self.stored else "items": self.items}
