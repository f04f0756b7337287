"""The one ``Analysis`` every command and the Python API build: the response analysis, with
the camera judgement beside it when there is video to judge camera commands by."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from analyzer.analysis.response import ResponseAnalyzer, Settings
from analyzer.extras import VIDEO, not_installed_note
from analyzer.pipeline import Stage
from analyzer.protocol.types import Event

if TYPE_CHECKING:  # PyAV and OpenCV: imported only for an analysis with video
    from analyzer.analysis.camera.source import VideoSource
    from analyzer.analysis.camera.stage import CameraJudge

NOT_JUDGED = "camera commands not judged from the recording's video"
WITHOUT_VIDEO = "camera commands not judged: the events came without their video"


class Judging(Protocol):
    """A stage that says how early a finding still to come may be (the response analysis,
    with or without the camera judgement): what the findings' time order needs."""

    def process(self, events: list[Event]) -> list[Event]: ...

    def close(self) -> list[Event]: ...

    def earliest_pending(self) -> float | None: ...


class WithCamera:
    """The response analysis and the camera judgement as one stage: both see every batch;
    a finding still to come is as early as the earlier of theirs."""

    def __init__(self, response: ResponseAnalyzer, camera: CameraJudge) -> None:
        self.response = response
        self.camera = camera

    def process(self, events: list[Event]) -> list[Event]:
        return [*self.response.process(events), *self.camera.process(events)]

    def close(self) -> list[Event]:
        return [*self.response.close(), *self.camera.close()]

    def earliest_pending(self) -> float | None:
        times = [self.response.earliest_pending(), self.camera.earliest_pending()]
        known = [t for t in times if t is not None]
        return min(known) if known else None


@dataclass(frozen=True)
class Analysis:
    """What a command analyses with: its ``settings`` and the ``video`` (a ``VideoSource``)
    its camera commands are judged by, if any.

    ``camera_note`` says, in one line, why camera commands that could have been judged
    were not (the video extra is missing; the events came without their video); it is
    empty when they are judged or there is no video to judge them by. ``keep_pictures``
    keeps each camera finding's two frames (the report shows them). Every command builds
    it with ``of_file`` (an input file) or directly (a live video, none at all), and runs
    ``stages()`` in its pipeline or ``judging()`` where the findings' order is needed."""

    settings: Settings = field(default_factory=Settings)
    video: VideoSource | None = None
    keep_pictures: bool = False
    camera_note: str = ""

    @classmethod
    def of_file(
        cls,
        path: str | os.PathLike[str] | None,
        settings: Settings | None = None,
        *,
        keep_pictures: bool = False,
    ) -> Analysis:
        """The analysis of an input file: its camera commands judged from its video when it
        is a recording with video (and the video extra is installed; else ``camera_note``
        says so)."""
        settings = settings or Settings()
        from analyzer.mcapio.read.video_window import has_video

        if path is None or str(path) == "-" or not has_video(path):
            return cls(settings)
        missing = not_installed_note(VIDEO, NOT_JUDGED)
        if missing is not None:
            return cls(settings, camera_note=missing)
        from analyzer.analysis.camera.source import RecordingVideo

        return cls(settings, RecordingVideo(path), keep_pictures=keep_pictures)

    @property
    def judges_camera(self) -> bool:
        return self.video is not None

    def judging(self) -> ResponseAnalyzer | WithCamera:
        """A new analysis stage: the response analysis, with the camera judgement beside it
        when there is video."""
        response = ResponseAnalyzer(self.settings)
        camera = self.camera_judge()
        return response if camera is None else WithCamera(response, camera)

    def stages(self, before_camera: Stage | None = None) -> list[Stage]:
        """The analysis as a pipeline's stages: the response analysis, then the camera
        judgement (after ``before_camera``, the stage that brings a live video its frames)."""
        stages: list[Stage] = [ResponseAnalyzer(self.settings)]
        if before_camera is not None:
            stages.append(before_camera)
        camera = self.camera_judge()
        if camera is not None:
            stages.append(camera)
        return stages

    def camera_judge(self) -> CameraJudge | None:
        if self.video is None:
            return None
        from analyzer.analysis.camera.stage import CameraJudge

        return CameraJudge(
            self.video, self.settings.time_allowed_s, keep_pictures=self.keep_pictures
        )

    def tell(self, note: Callable[[str], object]) -> Analysis:
        """``note`` the camera note, if any (a command's stderr line, a library's warning)."""
        if self.camera_note:
            note(self.camera_note)
        return self
