"""Where a command's analysis takes in the camera judgement: beside the response analysis."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Protocol

from analyzer.extras import VIDEO, not_installed_note
from analyzer.protocol.types import Event

if TYPE_CHECKING:  # PyAV and OpenCV: imported only for a recording with video
    from analyzer.analysis.camera.stage import CameraJudge

NOT_JUDGED = "camera commands not judged from the recording's video"


class Judging(Protocol):
    """A stage that says how early a finding still to come may be (the response analysis)."""

    def process(self, events: list[Event]) -> list[Event]: ...

    def close(self) -> list[Event]: ...

    def earliest_pending(self) -> float | None: ...


class WithCamera:
    """The response analysis and the camera judgement as one stage: both see every batch;
    a finding still to come is as early as the earlier of theirs."""

    def __init__(self, analysis: Judging, camera: CameraJudge) -> None:
        self.analysis = analysis
        self.camera = camera

    def process(self, events: list[Event]) -> list[Event]:
        return [*self.analysis.process(events), *self.camera.process(events)]

    def close(self) -> list[Event]:
        return [*self.analysis.close(), *self.camera.close()]

    def earliest_pending(self) -> float | None:
        times = [self.analysis.earliest_pending(), self.camera.earliest_pending()]
        known = [t for t in times if t is not None]
        return min(known) if known else None


def camera_judge(
    path: str | os.PathLike[str] | None,
    time_allowed_s: float,
    *,
    keep_pictures: bool = False,
    note: Callable[[str], object] | None = None,
) -> CameraJudge | None:
    """The camera judgement of an input file when it is a recording with video (None
    otherwise: nothing to judge camera commands with). Without the video extra there is
    none either, and ``note`` is told so in one line."""
    from analyzer.mcapio.read.video_window import has_video

    if path is None or str(path) == "-" or not has_video(path):
        return None
    missing = not_installed_note(VIDEO, NOT_JUDGED)
    if missing is not None:
        if note is not None:
            note(missing)
        return None
    from analyzer.analysis.camera.source import RecordingVideo
    from analyzer.analysis.camera.stage import CameraJudge

    return CameraJudge(RecordingVideo(path), time_allowed_s, keep_pictures=keep_pictures)


def with_camera(analysis: Judging, camera: CameraJudge | None) -> Judging:
    """``analysis`` with the camera judgement beside it (``analysis`` itself without)."""
    return analysis if camera is None else WithCamera(analysis, camera)


def camera_stages(
    path: str | os.PathLike[str] | None,
    time_allowed_s: float = 5.0,
    note: Callable[[str], object] | None = None,
) -> Sequence[CameraJudge]:
    """The camera judgement as extra stages of a file's pipeline (none without video)."""
    camera = camera_judge(path, time_allowed_s, note=note)
    return [] if camera is None else [camera]
