"""`gimbal-analyzer record`: capture a live source into an MCAP recording."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable
from typing import IO, Any

from analyzer.bus_figures import status_words
from analyzer.commands.video_options import video_summary
from analyzer.errors import EXIT_FAILED, SourceError, UsageError
from analyzer.link_status import LinkStatus
from analyzer.live.options import add_foxglove_options
from analyzer.mcapio.write.options import add_compression_argument
from analyzer.pipeline import Batch
from analyzer.timefmt import UTC, TimeZone
from analyzer.video.spec import VIDEO_HOLD_BACK_S, add_video_options, is_camera_event

HELP = "capture a live source (CAN, TCP, proxy, serial, file replay) into an MCAP recording"
DESCRIPTION = f"""\
Capture everything a source delivers into an MCAP file that opens in Foxglove:
decoded events (one JSON channel per topic), the raw CAN frames / stream bytes
(so the recording can be decoded again by a later version), UAV and ranging
target positions for the Map panel and diagnostics for the Log panel.

The file is flushed every half second: if the recorder is killed, everything
older than about a second can still be read (gimbal-analyzer info / decode);
with --video, older than about {VIDEO_HOLD_BACK_S + 0.5:g} s (see "camera video" below).
Ctrl-C or SIGTERM finishes the file properly.

Sources (gimbal-analyzer interfaces lists the adapters of this machine):
  can:socketcan:can0            a CAN interface (received passively, never transmits)
  can:slcan:/dev/serial/by-id/usb-...-if00@1000000
                                a USB slcan adapter (CANable), opened listen-only
  tcp:192.168.42.200:2000       the IDU's TCP port (reconnects when the link drops)
  tcp:2000                      a port alone is on this machine, 127.0.0.1:2000 (simulate)
  proxy:2000->192.168.42.200:2000   between ground station and IDU, both directions
                                (listens on all interfaces; proxy:127.0.0.1:2000->...
                                does not; quoted in a shell, which takes > to redirect)
  serial:/dev/ttyUSB0@115200    the UART pins
  file:flight.log               replay a capture file (--speed 1 = recorded speed)

A CAN adapter or serial port that fails mid-capture (unplugged, interface down) is
opened again when it is back, with the same backoff as tcp: (0.5 s doubling to
10 s); the recording goes on. One that cannot be opened at the start is an error.

Examples:
  gimbal-analyzer record --source can:socketcan:can0 -o flight.mcap
  gimbal-analyzer record --source tcp:192.168.42.200:2000 -o bench.mcap --duration 600
  gimbal-analyzer record --source 'proxy:2000->192.168.42.200:2000' -o gs.mcap --tui
  gimbal-analyzer record --source can:socketcan:can0 -o flight.mcap --foxglove
                                watch it live in Foxglove too (ws://127.0.0.1:8765)
  gimbal-analyzer record --source tcp:192.168.42.200:2000 -o flight.mcap --video main
"""

STATUS_INTERVAL_TTY = 0.5
STATUS_INTERVAL_LOG = 10.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--source", required=True, metavar="SPEC", help="what to capture")
    parser.add_argument("-o", "--output", required=True, metavar="FILE", help="MCAP file")
    parser.add_argument("--tui", action="store_true", help="watch the capture in the monitor UI")
    parser.add_argument(
        "--duration", type=float, metavar="S", help="stop after S seconds (default: until Ctrl-C)"
    )
    parser.add_argument(
        "--speed",
        type=float,
        metavar="X",
        help="file: sources only: replay at X times the recorded speed (default: as fast as read)",
    )
    parser.add_argument(
        "--print", action="store_true", help="also print every event as a JSON line on stdout"
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="no status line")
    add_compression_argument(parser)
    add_foxglove_options(parser)
    add_video_options(parser)
    parser.add_argument(
        "-f",
        "--force",
        action="store_true",
        help="replace an existing output file (never the source's own file, never a symlink)",
    )


class EventPrinter:
    """Sink printing each event as one JSON line."""

    def __init__(self, stream: IO[str]) -> None:
        self.stream = stream

    def handle(self, batch: Batch) -> None:
        write = self.stream.write
        for event in batch.events:
            write(json.dumps(event.to_dict(), default=str) + "\n")
        if batch.events:
            self.stream.flush()

    def close(self) -> None:
        self.stream.flush()


def _megabytes(path: str) -> str:
    try:
        return f"{os.path.getsize(path) / 1e6:.1f} MB"
    except OSError:
        return "? MB"


class LinkWatch:
    """Sink following the source's link state (for the status line and the final word)."""

    def __init__(self) -> None:
        self.status = LinkStatus()

    def handle(self, batch: Batch) -> None:
        self.status.fold(e for e in batch.events if not is_camera_event(e))

    def close(self) -> None:
        pass

    def last_words(self) -> str:
        """The last link message worth reporting at the end (a failure before a retry)."""
        return self.status.problem or self.status.detail


class StatusLine:
    """Sink writing a short status line to stderr (overwritten in place on a terminal).

    Besides the counts it says what the link is doing (connecting, refused, connected,
    lost, retrying in N s), so a capture that receives nothing says why.
    """

    def __init__(
        self,
        stream: IO[str],
        path: str,
        link: LinkWatch | None = None,
        waiting: str = "waiting for data",
        zone: TimeZone = UTC,
    ) -> None:
        self.stream = stream
        self.zone = zone  # the times it shows (when the link was lost, the worst bus state)
        self.path = path
        self.link = link or LinkWatch()
        self.waiting = waiting
        self.tty = stream.isatty()
        self.interval = STATUS_INTERVAL_TTY if self.tty else STATUS_INTERVAL_LOG
        self.capture: Any = None
        self.notes: list[Callable[[], str]] = []  # more parts (the live server's)
        self.video: Any = None  # a VideoRecorder: its streams are shown too
        self._next = time.monotonic() + self.interval
        self._width = 0
        self._link_shown = ""

    def line(self) -> str:
        stats = self.capture.stats if self.capture is not None else None
        if stats is None:
            return f"recording {self.path}"
        parts = [f"recording {self.path}", f"{stats.elapsed_s:7.1f} s", self.link_words(stats)]
        if stats.frames or not stats.chunks:
            parts.append(f"{stats.frames} frames ({stats.frames_per_s:.0f}/s)")
        if stats.chunks:
            parts.append(f"{stats.bytes} bytes ({stats.bytes_per_s:.0f}/s)")
        words = status_words(stats.tally.bus, self.zone)
        if words is not None:  # error frames seen: the words of the monitor's status bar
            parts.append("  ".join(words.words()))
        parts.append(f"{stats.events} events")
        parts.append(f"{stats.diagnostics} diagnostics")
        if self.video is not None:
            parts.append(self.video.words())
        if stats.dropped:  # the capture fell behind: say so where the user looks
            parts.append(f"{stats.dropped} DROPPED")
        parts += [text for note in self.notes if (text := note())]
        parts.append(_megabytes(self.path))
        return "  ".join(parts)

    def link_words(self, stats: Any) -> str:
        link = self.link.status
        if link.seen:
            return f"[{link.describe(time.time(), self.zone)}]"
        return "[receiving]" if stats.frames or stats.chunks else f"[{self.waiting}]"

    def handle(self, batch: Batch) -> None:
        now = time.monotonic()
        link = self.link.status
        change = link.problem if link.failing else link.detail
        if change != self._link_shown and not self.tty:
            self._next = now  # a log gets every change of the link at once
        self._link_shown = change
        if now < self._next:
            return
        self._next = now + self.interval
        self._show(self.line())

    def _show(self, text: str) -> None:
        if self.tty:
            pad = max(0, self._width - len(text))
            self.stream.write("\r" + text + " " * pad)
            self._width = len(text)
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def close(self) -> None:
        error = getattr(self.capture, "error", None)
        if error is not None:
            self._show(f"{self.line()}  STOPPED: {error}")
        if self.tty and self._width:
            self.stream.write("\n")
            self.stream.flush()


def _input_files(spec: str) -> list[str]:
    """The file a ``file:`` source reads (the recording must never replace it)."""
    from analyzer.sources.spec import FileSpec, parse_source

    try:
        parsed = parse_source(spec)
    except Exception:  # open_source reports a bad spec with the full explanation
        return []
    return [parsed.path] if isinstance(parsed, FileSpec) else []


def run(args: argparse.Namespace) -> int:
    from analyzer.commands.live_recording import open_live_recording
    from analyzer.commands.video_options import video_metadata
    from analyzer.live.attach import foxglove_note
    from analyzer.mcapio.write.sink import recording_metadata
    from analyzer.output_file import check_output
    from analyzer.sources import open_source

    inputs, hold_back = _checked_arguments(args)
    target = check_output(args.output, force=args.force, inputs=inputs)
    path = str(target)
    run_app = _monitor_app() if args.tui else None
    source = open_source(args.source, replay_speed=args.speed)
    description = str(getattr(source, "description", args.source))
    note = getattr(source, "listen_note", None)
    if note and not args.tui:  # where a proxy listens: said at start, whatever --quiet
        print(f"{description}: {note}", file=sys.stderr, flush=True)
    link = LinkWatch()
    status: StatusLine | None = None

    def own_sinks(sink: Any, video: Any) -> list[Any]:
        nonlocal status
        own: list[Any] = [link]
        if not args.quiet and not args.tui:
            address = getattr(source, "address", None)
            waiting = f"connecting to {address}" if address else "waiting for data"
            status = StatusLine(sys.stderr, path, link, waiting, args.time_zone)
            status.video = video
            own.append(status)
        if args.print and not args.tui:
            own.append(EventPrinter(sys.stdout))
        return own

    recording = open_live_recording(
        args,
        source,
        path,
        metadata=recording_metadata(
            description, spec=args.source, command="record", **video_metadata(args)
        ),
        hold_back=hold_back,
        sinks_after=own_sinks,
        inputs=inputs,
    )
    if status is not None:
        live = recording.live
        status.notes.append(lambda: foxglove_note(live))
        status.capture = recording.capture
    result = recording.run(
        args.duration,
        tui=run_app,
        label=description,
        exit_when_done=args.duration is not None,
    )
    return _said_at_the_end(args, recording, link, description, bool(inputs), result)


def _checked_arguments(args: argparse.Namespace) -> tuple[list[str], float]:
    """The input files of a file: source and the video's hold-back, once the options are
    seen to go together (a UsageError before anything starts otherwise)."""
    from analyzer.video.spec import video_specs

    if args.duration is not None and not args.duration > 0:
        raise UsageError("--duration must be a positive number of seconds")
    if args.tui and not (sys.stdin.isatty() and sys.stdout.isatty()):
        raise UsageError(
            "record --tui needs a terminal; leave out --tui to record with a status line "
            "on standard error"
        )
    inputs = _input_files(args.source)
    # a wrong --video is a usage error before anything starts; video needs the hold-back
    hold_back = VIDEO_HOLD_BACK_S if video_specs(args) else 0.0
    if hold_back and inputs:
        raise UsageError(
            "--video records a live camera next to a live source; a file: replay has the "
            "times of its recording"
        )
    return inputs, hold_back


def _monitor_app() -> Any:
    """The monitor UI's runner (--tui), or a UsageError when it cannot be loaded."""
    try:
        from analyzer.tui.app import run_app
    except ImportError as exc:
        raise UsageError(f"the monitor UI is not available ({exc})") from None
    return run_app


def _said_at_the_end(
    args: argparse.Namespace,
    recording: Any,
    link: LinkWatch,
    description: str,
    from_file: bool,
    result: int,
) -> int:
    """What the recording ended with, on standard error; the exit code (a capture error,
    nothing received or a silent video stream fail it)."""
    from analyzer.live.attach import foxglove_summary

    capture, sink, video, live = recording.capture, recording.sink, recording.video, recording.live
    path = recording.path
    stats = capture.stats
    if sink.error is not None:
        raise SourceError(sink.error)
    if capture.error is not None:
        print(
            f"gimbal-analyzer record: {capture.error}; the recording {path} is finished "
            "and keeps everything up to then",
            file=sys.stderr,
        )
        result = 1
    nothing_received = result == 0 and not from_file and not (stats.frames or stats.chunks)
    reason = capture.stop_reason or "stopped"
    if not args.quiet:
        print(
            f"recorded {stats.frames} frames, {stats.chunks} stream chunks, "
            f"{stats.events} events, {stats.diagnostics} diagnostics in {stats.elapsed_s:.1f} s "
            f"to {path} ({_megabytes(path)}); ended: {reason}",
            file=sys.stderr,
        )
        if live is not None:
            print(foxglove_summary(live), file=sys.stderr)
    if video is not None and not args.quiet:
        print(f"{video_summary(video)}", file=sys.stderr)
    if nothing_received:
        _say_nothing_received(link, video, description, stats.elapsed_s, path)
        result = EXIT_FAILED
    if not nothing_received and not from_file and link.status.failing:
        # an adapter unplugged and not back: the recording ends at the loss, say so
        print(
            f"gimbal-analyzer record: warning: {description} had not come back when the "
            f"capture ended ({link.status.describe(time.time(), args.time_zone)})",
            file=sys.stderr,
        )
    return _said_of_the_video_and_drops(video, stats, result)


def _say_nothing_received(
    link: LinkWatch, video: Any, description: str, elapsed_s: float, path: str
) -> None:
    """A live source that delivered nothing is a failed capture (exit 1), not a success:
    say why we think nothing came (the last link message)."""
    from analyzer.commands.video_options import video_frames

    last = link.last_words()
    pictures = video_frames(video) if video is not None else None
    holds = f"{pictures} and its link diagnostics" if pictures else "only its link diagnostics"
    print(
        f"gimbal-analyzer record: nothing was received from {description} in "
        f"{elapsed_s:.1f} s"
        + (f" (last link message: {last})" if last else "")
        + f"; the recording {path} holds {holds}",
        file=sys.stderr,
    )


def _said_of_the_video_and_drops(video: Any, stats: Any, result: int) -> int:
    """A video stream that never delivered, frames dropped: said even with --quiet."""
    from analyzer.commands.video_options import silent_streams

    for words in silent_streams(video) if video is not None else []:
        # A stream asked for that never delivered is a failure, even with --quiet.
        print(f"gimbal-analyzer record: {words}", file=sys.stderr)
        if result == 0:
            result = EXIT_FAILED
    if stats.dropped:  # even with --quiet: the recording is missing data
        print(
            f"gimbal-analyzer record: warning: {stats.dropped} frame(s) / chunk(s) "
            f"({stats.dropped_bytes} bytes) dropped because the capture fell behind the "
            "source; link diagnostics of state 'overflow' in the recording mark where",
            file=sys.stderr,
        )
    return result
