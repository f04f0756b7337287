"""The run of a live capture into a recording, shared by `record` and `demo`."""

from __future__ import annotations

import argparse
import contextlib
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from analyzer.errors import SourceError
from analyzer.timefmt import UTC, TimeZone

if TYPE_CHECKING:
    from analyzer.capture import Capture
    from analyzer.commands.video_options import SimulatedStreams
    from analyzer.live.server import FoxgloveLive
    from analyzer.mcapio.write.sink import McapSink
    from analyzer.mcapio.write.video import VideoRecorder


@dataclass
class Companion:
    """Something that runs beside the capture (the demo's simulated scene): started right
    after the capture, stopped first when the run ends (also by ``--duration``)."""

    start: Callable[[], None]
    stop: Callable[[], None]


@dataclass
class LiveRecording:
    """A source captured into ``sink``, with the camera video and the live Foxglove server
    when asked for; ``run`` drives it in the monitor UI or until the source ends, Ctrl-C,
    SIGTERM or ``duration``, and always finishes the file."""

    capture: Capture
    sink: McapSink
    path: str
    source: Any
    video: VideoRecorder | None = None
    live: FoxgloveLive | None = None
    companions: list[Companion] = field(default_factory=list)
    zone: TimeZone = UTC  # the monitor's times (--local-time: local time)

    def run(
        self,
        duration: float | None,
        *,
        tui: Callable[..., Any] | None = None,
        label: str = "",
        exit_when_done: bool = False,
        started: Callable[[], None] | None = None,
    ) -> int:
        """Run to the end; the exit code of the monitor UI or of the capture (0 / 1).

        ``tui`` is ``analyzer.tui.app.run_app`` to watch in the monitor; ``started`` is
        called (plain run only) just before the capture starts, for a first line."""
        from analyzer.capture import run_until_interrupted
        from analyzer.live.attach import foxglove_status, with_foxglove

        def finish() -> None:
            self.capture.stop()
            for companion in self.companions:
                companion.stop()

        timer: threading.Timer | None = None
        if duration is not None:
            timer = threading.Timer(duration, finish)
            timer.daemon = True
        if self.video is not None:
            self.video.start()
        try:
            if tui is not None:
                self._start_companions()
                if timer is not None:
                    timer.start()
                return int(
                    tui(
                        self.capture,
                        recording=self.path,
                        source_label=with_foxglove(label, self.live),
                        exit_when_done=exit_when_done,
                        live_status=foxglove_status(self.live),
                        zone=self.zone,
                    )
                )
            # Inside the try: a failed write here must still finish the recording.
            if started is not None:
                started()
            self.capture.start()
            self._start_companions()
            if timer is not None:
                timer.start()
            return run_until_interrupted(self.capture)
        finally:
            if timer is not None:
                timer.cancel()
            for companion in self.companions:
                companion.stop()
            if self.video is not None:
                self.video.stop()
            if self.capture.running:
                self.capture.stop()
                self.capture.join()
            self.source.close()  # the capture closes it too; here for a failure before
            with contextlib.suppress(SourceError):  # a write error is reported after
                self.sink.close()  # normally done by the capture; the file is finished

    def _start_companions(self) -> None:
        for companion in self.companions:
            companion.start()


def open_live_recording(
    args: argparse.Namespace,
    source: Any,
    path: str,
    *,
    metadata: dict[str, Any],
    hold_back: float,
    sinks_after: Callable[[McapSink, Any], Sequence[Any]] = lambda sink, video: (),
    simulated_camera: SimulatedStreams | None = None,
    **sink_options: Any,
) -> LiveRecording:
    """The MCAP sink of ``path``, the ``--video`` recorder and the ``--foxglove`` server
    around a capture of ``source`` with the analysis stages; ``sinks_after`` gives the
    command's own sinks (printers, status line); ``simulated_camera`` makes the streams of
    ``--camera sim`` (demo's). On a failure the source and the live
    server are closed before the error goes on."""
    from analyzer.analysis.stage import Analysis
    from analyzer.capture import Capture
    from analyzer.commands.video_options import video_recorder
    from analyzer.live.attach import start_foxglove
    from analyzer.mcapio.write.sink import McapSink

    live: FoxgloveLive | None = None
    try:
        live = start_foxglove(args)  # said on start, like the proxy's address
        sink = McapSink(
            path,
            metadata=metadata,
            compression=args.compression,
            force=args.force,
            tee=live,
            hold_back=hold_back,
            zone=args.time_zone,
            **sink_options,
        )
    except BaseException:
        source.close()
        if live is not None:
            live.close()
        raise
    video = video_recorder(args, sink, simulated_camera)
    own = sinks_after(sink, video)
    sinks: list[Any] = [s for s in (video, sink, *own, live) if s is not None]
    stages = Analysis().stages(before_camera=None if video is None else video.stage)
    capture = Capture(source, sinks, stages=stages)
    return LiveRecording(capture, sink, path, source, video, live, zone=args.time_zone)
