"""The capture engine: a reader thread reads a live source and runs the pipeline on it."""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from types import FrameType
from typing import Any

from analyzer import wall_clock
from analyzer.errors import OutputError, SourceError
from analyzer.pipeline import Pipeline, PipelineDecoder, Sink, Stage
from analyzer.portable import STOP_SIGNALS
from analyzer.protocol.types import Event
from analyzer.sources.base import link_event
from analyzer.stdio import signals_to
from analyzer.tally import Tally

DEFAULT_BITRATE = 1_000_000

TICK_INTERVAL_S = 0.25  # how often the decoder is asked about stale partial messages
RATE_WINDOW_S = 1.0  # frames_per_s / bus_load_pct are averaged over this window
MAX_BATCH_ITEMS = 20_000  # a batch is handed over early when it grows this large
OUTPUT_CLOSED = "output closed"  # stop_reason when a printing sink's reader went away


class CaptureError(SourceError):
    """Why a capture stopped early (source failure, sink failure such as a full disk)."""


@dataclass(slots=True)
class CaptureStats:
    """Counters of a running capture (a snapshot is returned by ``Capture.stats``).

    The counts are those of the pipeline's tally (``analyzer.tally``), the same figures
    every command reports: ``bytes`` counts raw input bytes (stream bytes plus CAN data
    bytes), ``events`` every event (diagnostics included), ``diagnostics`` the
    /diagnostics events among them (link changes included), by kind in
    ``diagnostic_kinds``; ``tally`` is a copy of all of it. Rates are averaged over the
    last second.
    ``bus_load_pct`` estimates the load of the CAN bus (frame bit counts without stuffing,
    131 bits for an extended 8-byte frame) at the source's bitrate (1 Mbit/s by default).
    ``dropped`` / ``dropped_bytes`` count frames / chunks the source had to drop because
    the capture fell behind (its queue was full); each drop is also a link diagnostic.
    """

    frames: int = 0
    chunks: int = 0
    bytes: int = 0
    events: int = 0
    diagnostics: int = 0
    batches: int = 0
    frames_per_s: float = 0.0
    bytes_per_s: float = 0.0
    bus_load_pct: float = 0.0
    elapsed_s: float = 0.0
    dropped: int = 0
    dropped_bytes: int = 0
    diagnostic_kinds: dict[str, int] = field(default_factory=dict)
    tally: Tally = field(default_factory=Tally)

    def as_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out.pop("tally", None)
        return out


def _reason(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        where = f": {exc.filename}" if exc.filename else ""
        return f"{exc.strerror}{where}"
    lines = str(exc).strip().splitlines()
    return lines[0] if lines else exc.__class__.__name__


class Capture:
    """Reads ``source`` in a thread and runs the pipeline (``analyzer.pipeline``) on it:
    one Batch per ``batch_interval`` goes to every sink's ``handle()`` (possibly empty,
    so sinks can flush on time).

    The pipeline's decoder (a default ``Decoder()`` when None) gets every CAN frame /
    stream chunk; ``Event`` items of a source (link changes, pre-decoded file events) go
    straight into the batch; ``stages`` run on every batch. For live sources
    ``decoder.tick`` runs every 0.25 s on the source's clock (a file replay is decoded
    exactly as ``decode`` does it); ``decoder.close`` runs at the end. When the source
    ends, fails, ``stop()`` is called or a sink raises, the thread delivers a last batch
    to the sinks that still work, closes the source and closes every sink. Failures are
    kept in ``error`` (a CaptureError, one clear line); ``stop_reason`` says why it
    ended: "end of input", "stopped", "error", or "output closed" when a sink's reader
    went away (BrokenPipeError: a quiet stop, not an error).
    """

    def __init__(
        self,
        source: Any,
        sinks: Sequence[Sink],
        *,
        decoder: PipelineDecoder | None = None,
        stages: Sequence[Stage] = (),
        batch_interval: float = 0.05,
    ) -> None:
        if batch_interval <= 0:
            raise ValueError("batch_interval must be positive")
        self.source = source
        self.pipeline = Pipeline(sinks, decoder=decoder, stages=stages)
        self.batch_interval = batch_interval
        self.bitrate: int = int(getattr(source, "bitrate", 0) or DEFAULT_BITRATE)
        self.live = bool(getattr(source, "live", True))
        self.error: CaptureError | None = None
        self.stop_reason: str = ""
        self._rates = (0.0, 0.0, 0.0)  # frames/s, bytes/s, bus load %
        self._window: deque[tuple[float, int, int, int]] = deque()
        self._stop = threading.Event()
        self._done = threading.Event()
        self._reported = 0  # sink failures already turned into ``error``
        self._batches = 0
        self._notes: list[Event] = []
        self._thread: threading.Thread | None = None
        self._started_at = 0.0
        self._ended_at = 0.0  # when the reader stopped: elapsed time stops there
        self._last_item = (0.0, 0.0)  # (source time, monotonic time) of the newest item
        self._source_name = str(getattr(source, "source_name", "capture"))

    @property
    def sinks(self) -> list[Sink]:
        return self.pipeline.sinks

    @property
    def decoder(self) -> PipelineDecoder:
        return self.pipeline.decoder

    # -- control ---------------------------------------------------------------------------------

    def start(self) -> None:
        if self._thread is not None:
            raise RuntimeError("capture already started")
        self._started_at = time.monotonic()
        self._window.append((self._started_at, 0, 0, 0))
        self._thread = threading.Thread(target=self._run, name="capture", daemon=True)
        self._thread.start()

    def add_sink(self, sink: Sink) -> None:
        """Attach one more sink, before ``start()`` or while running (from the next batch on)."""
        self.pipeline.sinks.append(sink)

    def stop(self) -> None:
        """Ask the reader thread to finish (returns at once; use join/wait to wait)."""
        self._stop.set()

    def join(self, timeout: float | None = None) -> bool:
        """Wait for the thread to finish; True when it has."""
        if self._thread is None:
            return True
        self._thread.join(timeout)
        return not self._thread.is_alive()

    def wait(self) -> None:
        """Block until the source ends, a failure stops it or ``stop()`` is called elsewhere."""
        if self._thread is None:
            return
        while not self._done.wait(0.2):
            pass
        self._thread.join()

    @property
    def running(self) -> bool:
        return self._thread is not None and not self._done.is_set()

    @property
    def stats(self) -> CaptureStats:
        tally = self.pipeline.snapshot()
        frames_per_s, bytes_per_s, load = self._rates
        snapshot = CaptureStats(
            frames=tally.frames,
            chunks=tally.chunks,
            bytes=tally.bytes,
            events=tally.events,
            diagnostics=tally.diagnostics,
            batches=self._batches,
            frames_per_s=frames_per_s,
            bytes_per_s=bytes_per_s,
            bus_load_pct=load,
            diagnostic_kinds=dict(tally.kinds),
            tally=tally,
        )
        if self._started_at:
            end = self._ended_at or time.monotonic()
            snapshot.elapsed_s = end - self._started_at
        snapshot.dropped = int(getattr(self.source, "dropped_items", 0))
        snapshot.dropped_bytes = int(getattr(self.source, "dropped_bytes", 0))
        return snapshot

    # -- the reader thread ------------------------------------------------------------------------

    def _run(self) -> None:
        try:
            self._loop()
        except Exception as exc:  # a bug in a decoder or source: end cleanly, keep the reason
            self._fail(f"capture failed: {exc.__class__.__name__}: {exc}", exc)
        finally:
            self._finish()

    def _loop(self) -> None:
        pipeline = self.pipeline
        interval = self.batch_interval
        now = time.monotonic()
        next_flush = now + interval
        next_tick = now + TICK_INTERVAL_S
        while not self._stop.is_set():
            wait = min(max(0.0, next_flush - time.monotonic()), interval)
            try:
                items = self.source.read(wait)
            except EOFError:
                self.stop_reason = "end of input"
                return
            except SourceError as exc:  # sources name themselves in their messages
                self._fail(_reason(exc), exc)
                return
            except Exception as exc:
                self._fail(f"{self._describe_source()} failed: {_reason(exc)}", exc)
                return
            if items:
                pipeline.feed(items)
                last = items[-1]
                if not isinstance(last, Event):
                    self._last_item = (last.time, time.monotonic())
            now = time.monotonic()
            if now >= next_tick:
                next_tick = now + TICK_INTERVAL_S
                self._tick(now)
            if now >= next_flush or pipeline.pending_items >= MAX_BATCH_ITEMS:
                self._deliver()
                next_flush = max(next_flush + interval, now)
        if not self.stop_reason:
            self.stop_reason = "stopped"

    def _describe_source(self) -> str:
        return str(getattr(self.source, "description", "source"))

    def _tick(self, now: float) -> None:
        source_time, seen_at = self._last_item
        if seen_at and self.live:
            self.pipeline.tick(source_time + (now - seen_at))

    def _rate(self) -> None:
        tally = self.pipeline.tally
        now = time.monotonic()
        window = self._window
        window.append((now, tally.frames, tally.bits, tally.bytes))
        while len(window) > 2 and now - window[1][0] >= RATE_WINDOW_S:
            window.popleft()
        t0, frames0, bits0, bytes0 = window[0]
        span = now - t0
        if span > 0:
            self._rates = (
                (tally.frames - frames0) / span,
                (tally.bytes - bytes0) / span,
                100.0 * (tally.bits - bits0) / span / self.bitrate,
            )

    def _deliver(self) -> None:
        self.pipeline.deliver(wall_clock.now())
        self._batches += 1
        self._rate()
        self._report_sink_failures()

    def _report_sink_failures(self) -> None:
        failures = self.pipeline.failures
        while self._reported < len(failures):
            failure = failures[self._reported]
            self._reported += 1
            exc = failure.error
            if isinstance(exc, BrokenPipeError):
                # The reader of a printed output went away (| head): stop as asked.
                self.stop_reason = OUTPUT_CLOSED
                self._stop.set()
            elif isinstance(exc, OutputError):  # says itself what could not be written
                self._fail(str(exc), exc)
            elif isinstance(exc, SourceError):  # says what failed (disk full: cannot write...)
                self._fail(_reason(exc), exc)
            else:
                name = failure.sink.__class__.__name__
                verb = "failed while closing" if failure.closing else "failed"
                self._fail(f"{name} {verb}: {_reason(exc)}", exc)

    def _fail(self, message: str, exc: BaseException | None) -> None:
        """Keep the first failure, stop the loop, and note it in the last batch."""
        if self.error is None:
            error = CaptureError(message)
            error.__cause__ = exc
            self.error = error
        self.stop_reason = "error"
        self._stop.set()
        self._notes.append(link_event(self._source_name, message, "failed"))

    def _finish(self) -> None:
        self._ended_at = time.monotonic()
        try:
            with contextlib.suppress(Exception):
                self.source.close()
            try:
                notes, self._notes = self._notes, []
                self.pipeline.finish(wall_clock.now(), notes)
            except Exception as exc:
                self._fail(f"decoder failed at the end: {_reason(exc)}", exc)
                self.pipeline.finished = True
            self._batches += 1
            self._rate()
            self._report_sink_failures()
        finally:
            self._done.set()


def run_until_interrupted(capture: Capture) -> int:
    """Run ``capture`` (starting it if needed) until its source ends or Ctrl-C / SIGTERM.

    The first Ctrl-C or SIGTERM stops the capture cleanly (sinks are closed, recordings
    finalised); a second Ctrl-C stops waiting (KeyboardInterrupt). Signal handlers are
    installed only in the main thread and restored afterwards. Returns 0, or 1 when the
    capture ended with an error (see ``capture.error``).
    """
    interrupted: list[int] = []

    def on_signal(signum: int, frame: FrameType | None) -> None:
        interrupted.append(signum)
        capture.stop()
        if signum == signal.SIGINT and len(interrupted) > 1:
            raise KeyboardInterrupt

    with signals_to((int(signal.SIGINT), *STOP_SIGNALS), on_signal):
        if capture._thread is None:
            capture.start()
        capture.wait()
    if interrupted and capture.error is None:
        capture.stop_reason = signal.Signals(interrupted[0]).name
    return 1 if capture.error is not None else 0
