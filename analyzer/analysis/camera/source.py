"""Where the judgement gets its pictures: a recording's video, read and decoded a window at once."""

from __future__ import annotations

import math
import os
from typing import Protocol

from analyzer.video.decode import Picture, decode_window

PICTURE_EVERY_S = 0.05  # pictures looked at: at most 20 a second (a 30 fps stream: 15)


class VideoSource(Protocol):
    """The camera streams of an input: their names, their pictures over a time window
    (decoded from the keyframe before it), and how far they reach (a live recording's
    video arrives later than the telemetry)."""

    def streams(self) -> list[str]: ...

    def pictures(self, stream: str, start: float, end: float) -> list[Picture]: ...

    def until(self) -> float: ...


class RecordingVideo:
    """The video of a recording (MCAP): the chunks of a window are read, the frames from the
    keyframe before it decoded, one picture kept every PICTURE_EVERY_S."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        from analyzer.mcapio.read.video_window import RecordedVideo

        self.video = RecordedVideo(path)
        self.frames_decoded = 0

    def streams(self) -> list[str]:
        return self.video.streams()

    def pictures(self, stream: str, start: float, end: float) -> list[Picture]:
        frames = self.video.frames(stream, start, end)
        if not frames:
            return []
        self.frames_decoded += len(frames)
        return decode_window(frames[0].codec, frames, start, every_s=PICTURE_EVERY_S)

    def until(self) -> float:
        return math.inf
