"""One camera stream in its own thread: RTSP demux (PyAV), access units, times, thumbnails."""

from __future__ import annotations

import re
import struct
import threading
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import av

from analyzer import wall_clock
from analyzer.protocol.types import Event
from analyzer.sources.backoff import Backoff
from analyzer.sources.base import OVERFLOW, link_event
from analyzer.video.annexb import (
    CODECS,
    H264,
    H265,
    AccessUnit,
    ParameterSets,
    annex_b,
    is_vcl,
    nal_type,
    parameter_sets_from_extradata,
    split_nals,
)
from analyzer.video.frame_clock import FrameClock, Stamp
from analyzer.video.spec import CAMERA_SOURCE_PREFIX, DEFAULT_THUMBNAIL_S, VideoSpec
from analyzer.video.thumbnail import jpeg_thumbnail

# What a stream may queue ahead of the recorder: about 30 s of a 1080p30 stream.
MAX_QUEUED_FRAMES = 900
MAX_QUEUED_BYTES = 64 * 1024 * 1024
OPEN_TIMEOUT_S = 5.0
READ_TIMEOUT_S = 5.0
STATE_REFUSED = "refused"
_PRFT = struct.Struct("<q")
_CREDENTIALS = re.compile(r"(rtsps?://[^:/@\s]*):[^@\s]*@")


@dataclass(slots=True)
class VideoFrame:
    """One access unit as recorded: Annex B ``data``, capture ``time`` (Unix seconds)."""

    stream: str
    time: float
    data: bytes
    keyframe: bool
    codec: str
    width: int
    height: int
    thumbnail: bytes | None = None


class StreamRefused(Exception):
    """The stream cannot be recorded as it is (B-frames, a codec Foxglove cannot play)."""


def describe_error(exc: BaseException) -> str:
    """Why a stream could not be opened or read, in words (401 unauthorized, refused...)."""
    if isinstance(exc, av.error.HTTPUnauthorizedError):
        return "401 unauthorized: wrong user name or password"
    if isinstance(exc, av.error.HTTPForbiddenError):
        return "403 forbidden: this user may not watch the stream"
    if isinstance(exc, av.error.HTTPNotFoundError):
        return "404 not found: the camera has no stream at that path"
    if isinstance(exc, av.error.ExitError | TimeoutError):
        return "timed out (no answer / no data)"
    text = getattr(exc, "strerror", None) or str(exc) or exc.__class__.__name__
    text = _CREDENTIALS.sub(r"\1@", text)  # FFmpeg's messages may name the URL: no password
    return text[:1].lower() + text[1:] if text[:2] != text[:2].upper() else text


class VideoStream:
    """Records one RTSP stream in a background thread.

    Packets are copied as the camera sent them (PyAV demuxer, no decoding except one
    keyframe per ``thumbnail_interval`` for the thumbnail). Packets of one picture are
    merged into one access unit in Annex B, with the parameter sets in front of every
    keyframe; the first frame after each (re)connection is a keyframe. A stream with
    B-frames is refused (Foxglove cannot play it). Frames wait in a bounded queue
    (``take``); when it is full, frames are dropped up to the next keyframe, counted and
    reported. Every change of the link is a ``link`` diagnostic of source
    ``camera/NAME``; a failed or lost stream is retried with the backoff of ``tcp:``.
    """

    def __init__(
        self,
        spec: VideoSpec,
        *,
        thumbnail_interval: float = DEFAULT_THUMBNAIL_S,
        backoff_initial: float = 0.5,
        backoff_max: float = 10.0,
        max_frames: int = MAX_QUEUED_FRAMES,
        max_bytes: int = MAX_QUEUED_BYTES,
    ) -> None:
        self.spec = spec
        self.source_name = f"{CAMERA_SOURCE_PREFIX}{spec.name}"
        self.thumbnail_interval = thumbnail_interval
        self.backoff = Backoff(backoff_initial, backoff_max)
        self.max_frames = max_frames
        self.max_bytes = max_bytes
        self.frames = 0  # frames queued for the recording
        self.dropped = 0  # frames lost because the queue was full (reported)
        self.skipped = 0  # frames before the first keyframe of a connection
        self._overflowed = False
        self.connections = 0
        self.state = ""
        self.last_problem = ""  # the last failure in words (for the final summary)
        self.last_reason = ""  # ... and its reason alone (for the status line)
        self._frames: deque[VideoFrame] = deque()
        self._events: deque[Event] = deque()
        self._queued_bytes = 0
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self._need_key = True
        self._last_thumbnail = float("-inf")
        self._thread = threading.Thread(target=self._main, name=f"video-{spec.name}", daemon=True)

    # -- control ----------------------------------------------------------------------------

    def start(self) -> None:
        self._thread.start()

    def request_stop(self) -> None:
        """Ask the thread to end (returns at once; ``stop`` waits for it)."""
        self._stopping.set()

    def stop(self, timeout: float = READ_TIMEOUT_S + 2) -> None:
        self._stopping.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout)

    def take(self) -> tuple[list[VideoFrame], list[Event]]:
        """Frames and link diagnostics that arrived since the last call."""
        with self._lock:
            frames = list(self._frames)
            self._frames.clear()
            self._queued_bytes = 0
            events = list(self._events)
            self._events.clear()
        return frames, events

    # -- the thread ---------------------------------------------------------------------------

    def _link(self, detail: str, state: str, **extra: Any) -> None:
        self.state = state
        if state in ("connect_failed", "lost", STATE_REFUSED):
            self.last_problem = detail
        event = link_event(self.source_name, detail, state, peer=self.spec.shown, **extra)
        with self._lock:
            self._events.append(event)

    def _main(self) -> None:
        shown = self.spec.shown
        while not self._stopping.is_set():
            self._link(f"connecting to {shown}", "connecting")
            got_frames = False
            try:
                got_frames = self._session()
            except StreamRefused as exc:
                self.last_reason = "refused: B-frames" if "B-frames" in str(exc) else "refused"
                self._link(f"{shown}: {exc}; not recorded", STATE_REFUSED)
                return
            except Exception as exc:  # every failure is reported and retried
                if self._stopping.is_set():
                    break
                lost = self.connections and self.state in ("connected", "resync")
                state = "lost" if lost else "connect_failed"
                verb = "connection lost" if state == "lost" else f"cannot open {shown}"
                self.last_reason = describe_error(exc)
                self._link(f"{verb}: {self.last_reason}", state)
            else:
                if self._stopping.is_set():
                    break
                self._link("connection lost: the camera ended the stream", "lost")
            if got_frames:
                self.backoff.reset()
            delay = self.backoff.failed()
            self._link(f"reconnecting in {delay:.1f} s", "reconnecting", retry_in_s=delay)
            if self._stopping.wait(delay):
                break

    def _session(self) -> bool:
        """One connection: read until it fails or ``stop``; True when frames came."""
        options = {"rtsp_transport": "tcp", "timeout": str(int(READ_TIMEOUT_S * 1e6))}
        container = av.open(
            self.spec.url, options=options, timeout=(OPEN_TIMEOUT_S, READ_TIMEOUT_S)
        )
        try:
            streams = container.streams.video
            if not streams:
                raise StreamRefused("the stream has no video")
            stream = streams[0]
            codec = {"h264": H264, "hevc": H265}.get(stream.codec_context.name, "")
            if codec not in CODECS:
                raise StreamRefused(f"video codec {stream.codec_context.name} (h264 or h265 only)")
            ctx = stream.codec_context
            rate = stream.average_rate or stream.guessed_rate or 30
            self.connections += 1
            self._link(
                f"connected to {self.spec.shown} ({codec} {ctx.width}x{ctx.height}, "
                f"{float(rate):.0f} fps)",
                "connected",
            )
            self._need_key = True
            assembler = _Assembler(codec, stream, float(rate))
            initial = parameter_sets_from_extradata(codec, ctx.extradata or b"")
            params = ParameterSets(codec, initial)
            clock: FrameClock[tuple[bytes, bool]] = FrameClock()
            got = False

            def queue(timed: list[tuple[float, tuple[bytes, bool]]]) -> bool:
                size = (codec, ctx.width, ctx.height)
                return any([self._queue(t, data, key, *size) for t, (data, key) in timed])

            for unit in assembler.units(container.demux(stream), self._stopping):
                if unit.restart:  # timestamps start over: a new anchor for the clock
                    got = queue(clock.flush()) or got
                    clock = FrameClock(not_before=clock.last)
                    self._link(
                        "the stream's timestamps went back at a keyframe (the camera restarted "
                        "it); capture times anchored again",
                        "resync",
                    )
                data, key = annex_b(codec, unit.units, params)
                stream_s = (unit.pts or 0) * assembler.time_base
                got = (
                    queue(clock.add(Stamp(stream_s, unit.arrival, unit.wallclock), (data, key)))
                    or got
                )
            return queue(clock.flush()) or got
        finally:
            container.close()

    def _queue(
        self, when: float, data: bytes, key: bool, codec: str, width: int, height: int
    ) -> bool:
        """Queue one frame for the recorder; False when it was not queued."""
        if self._need_key and not key and not self._overflowed:
            self.skipped += 1  # the start of a connection: wait for a keyframe
            return False
        thumbnail = None
        interval = self.thumbnail_interval
        if key and interval > 0 and when - self._last_thumbnail >= interval - 0.05:
            thumbnail = jpeg_thumbnail(codec, data)
            if thumbnail is not None:
                self._last_thumbnail = when
        frame = VideoFrame(self.spec.name, when, data, key, codec, width, height, thumbnail)
        with self._lock:
            full = len(self._frames) >= self.max_frames or (
                self._frames and self._queued_bytes + len(data) > self.max_bytes
            )
            if full or (self._need_key and not key):
                # after a drop, delta frames are useless until the next keyframe
                self.dropped += 1
                self._need_key = self._overflowed = True
                return False
            if self._overflowed:
                self._events.append(self._overflow())  # where the gap is: before this frame
                self._overflowed = False
            self._need_key = False
            self._frames.append(frame)
            self._queued_bytes += len(data)
            self.frames += 1
        return True

    def _overflow(self) -> Event:
        return link_event(
            self.source_name,
            f"{self.dropped} video frame(s) dropped in all: the recorder fell behind the camera "
            "and the video queue was full; recording resumed at a keyframe",
            OVERFLOW,
        )


class _Assembler:
    """Packets -> access units: packets of one picture (same pts, or no pts and no new
    picture start) are merged; a missing pts is filled from the frame interval; a pts
    going back (B-frames) refuses the stream."""

    def __init__(self, codec: str, stream: av.video.stream.VideoStream, rate: float) -> None:
        self.codec = codec
        self.time_base = float(stream.time_base or 1 / 90000)
        self.interval = max(1, round(1 / (rate or 30) / self.time_base))

    def units(
        self, packets: Iterator[av.Packet], stopping: threading.Event
    ) -> Iterator[AccessUnit]:
        pending: AccessUnit | None = None
        last_pts: int | None = None
        for packet in packets:
            if stopping.is_set():
                break
            if packet.size == 0:
                continue
            arrival = wall_clock.now()
            units = split_nals(bytes(packet))
            pts = packet.pts
            wallclock = _wallclock(packet)
            if pending is not None and self._same_picture(pending, pts, units):
                pending.units.extend(units)
                if pending.pts is None:
                    pending.pts = pts
                if pending.wallclock is None:
                    pending.wallclock = wallclock
                continue
            if pending is not None:
                last_pts = self._finish(pending, last_pts, pts)
                yield pending
            pending = AccessUnit(pts, arrival, wallclock, units)
        if pending is not None and not stopping.is_set():
            self._finish(pending, last_pts, None)
            yield pending

    def _same_picture(self, pending: AccessUnit, pts: int | None, units: list[bytes]) -> bool:
        if pts is not None and pending.pts is not None:
            return pts == pending.pts
        return not _starts_picture(self.codec, units) or not pending.has_picture(self.codec)

    def _finish(self, unit: AccessUnit, last: int | None, following: int | None) -> int:
        if unit.pts is None:
            if last is not None:
                unit.pts = last + self.interval
            elif following is not None:
                unit.pts = following - self.interval
            else:
                unit.pts = 0
        if last is not None and unit.pts < last and unit.keyframe(self.codec):
            unit.restart = True  # the camera restarted its stream (not a reordered frame)
        elif last is not None and unit.pts < last:
            raise StreamRefused(
                "the stream has B-frames (frames out of order), which Foxglove cannot play; "
                "set the camera's encoder to no B-frames (baseline profile)"
            )
        return unit.pts


def _starts_picture(codec: str, units: list[bytes]) -> bool:
    """True when the first slice begins a picture (first_mb_in_slice 0 /
    first_slice_segment_in_pic_flag), or when the packet opens with AUD / parameter sets."""
    for unit in units:
        kind = nal_type(codec, unit)
        if is_vcl(codec, kind):
            header = 2 if codec == H265 else 1
            return len(unit) > header and bool(unit[header] & 0x80)
    return True


def _wallclock(packet: av.Packet) -> float | None:
    """The capture time FFmpeg derived from the camera's RTCP sender reports, if any."""
    for side in packet.iter_sidedata():
        if side.data_type == "prft":
            return float(_PRFT.unpack_from(bytes(side))[0]) / 1e6
    return None
