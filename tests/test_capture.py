"""The capture engine: batching, decoding, ticking, end of input, and failures of sources and sinks."""

from __future__ import annotations

import errno
import os
import signal
import threading
import time
import uuid
from collections.abc import Iterable
from typing import Any

import can
import pytest

from analyzer.capture import Capture, CaptureError, run_until_interrupted
from analyzer.errors import SourceError
from analyzer.pipeline import Batch
from analyzer.protocol.codec import encode_command
from analyzer.protocol.feedback import encode_attitude
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID
from analyzer.protocol.types import (
    FROM_IDU,
    INCOMPLETE,
    LINK,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    CanFrame,
    Event,
    StreamChunk,
)
from analyzer.sources import open_source
from analyzer.tally import CAN_BITS_EXTENDED
from tests.platforms import posix_signals

DEADLINE_S = 5.0


class ListSink:
    def __init__(self) -> None:
        self.batches: list[Batch] = []
        self.closed = 0
        self.lock = threading.Lock()

    def handle(self, batch: Batch) -> None:
        with self.lock:
            self.batches.append(batch)

    def close(self) -> None:
        self.closed += 1

    @property
    def items(self) -> list[Any]:
        with self.lock:
            return [i for b in self.batches for i in b.items]

    @property
    def events(self) -> list[Event]:
        with self.lock:
            return [e for b in self.batches for e in b.events]


class ScriptedSource:
    """Hands out one prepared list per read, then ends (EOFError) or stays silent."""

    description = "scripted"
    source_name = "scripted"

    def __init__(self, reads: list[list[Any]], *, ends: bool = True) -> None:
        self.reads = list(reads)
        self.ends = ends
        self.closed = 0

    def read(self, timeout: float) -> list[Any]:
        if self.reads:
            return self.reads.pop(0)
        if self.ends:
            raise EOFError
        time.sleep(timeout)
        return []

    def close(self) -> None:
        self.closed += 1


class SpyDecoder:
    def __init__(self) -> None:
        from analyzer.protocol.decoder import ProtocolDecoder

        self.inner = ProtocolDecoder()
        self.ticks: list[float] = []
        self.closed = 0

    def feed_can(self, frame: CanFrame) -> list[Event]:
        return self.inner.feed_can(frame)

    def feed_stream(self, chunk: StreamChunk) -> list[Event]:
        return self.inner.feed_stream(chunk)

    def feed_batch(self, items: Iterable[object], events: list[Event], columns: Any = None) -> None:
        self.inner.feed_batch(items, events, columns)

    def tick(self, now: float) -> list[Event]:
        self.ticks.append(now)
        return self.inner.tick(now)

    def close(self, now: float | None = None) -> list[Event]:
        self.closed += 1
        return self.inner.close(now)


def wait_for(condition: Any) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.01)


def command_frame(t: float, **params: Any) -> CanFrame:
    return CanFrame(t, CONTROL_ID, encode_command("gimbal_control", **params))


def test_virtual_bus_command_is_decoded_and_handed_over_in_batches() -> None:
    channel = f"cap-{uuid.uuid4().hex[:8]}"
    sender = can.Bus(interface="virtual", channel=channel)
    sink = ListSink()
    capture = Capture(open_source(f"can:virtual:{channel}"), [sink], batch_interval=0.05)
    capture.start()
    try:
        data = encode_command("gimbal_control", pan_speed_dps=-5.0, tilt_speed_dps=0)
        for _ in range(500):
            sender.send(can.Message(arbitration_id=CONTROL_ID, data=data))
        wait_for(lambda: capture.stats.frames == 500)
    finally:
        capture.stop()
        assert capture.join(DEADLINE_S)
        sender.shutdown()
    assert capture.error is None and capture.stop_reason == "stopped"
    assert not capture.running
    assert sink.closed == 1
    frames = [i for i in sink.items if isinstance(i, CanFrame)]
    assert len(frames) == 500
    # batches, not one call per frame
    assert len(sink.batches) < 100
    assert max(len(b.items) for b in sink.batches) > 1
    commands = [e for e in sink.events if e.topic == TOPIC_COMMAND]
    assert len(commands) == 500
    assert commands[0].fields["name"] == "gimbal_control"
    assert commands[0].fields["pan_speed_dps"] == -5.0
    stats = capture.stats
    # events count every event: the 500 commands and the link diagnostic
    assert stats.frames == 500 and stats.events == 501 and stats.bytes == 4000
    assert stats.diagnostics == 1
    assert stats.diagnostic_kinds.get(LINK) == 1  # the "opened" notice
    assert all(b.wall_time > 0 for b in sink.batches)


def test_end_of_input_flushes_the_decoder_and_closes_everything() -> None:
    half_feedback = encode_attitude(pitch_deg=1.0, yaw_deg=2.0, motor_yaw_deg=3.0)[:16]
    reads: list[list[Any]] = [
        [command_frame(10.0, pan_speed_dps=1.0, tilt_speed_dps=0)],
        [
            CanFrame(10.1, FEEDBACK_ID, half_feedback[:8]),
            CanFrame(10.2, FEEDBACK_ID, half_feedback[8:]),
        ],
        [Event("/uav/text", 10.3, "file", {"text": "pre-decoded"})],
    ]
    source = ScriptedSource(reads)
    decoder = SpyDecoder()
    sink = ListSink()
    capture = Capture(source, [sink], decoder=decoder)
    capture.start()
    capture.wait()
    assert capture.stop_reason == "end of input" and capture.error is None
    assert decoder.closed == 1 and source.closed == 1 and sink.closed == 1
    topics = [e.topic for e in sink.events]
    assert topics[0] == TOPIC_COMMAND and "/uav/text" in topics
    incomplete = [e for e in sink.events if e.fields.get("kind") == INCOMPLETE]
    assert incomplete, "the half feedback message is reported at the end"
    assert len(sink.items) == 3


def test_stream_chunks_are_decoded_with_their_direction() -> None:
    frame = wrap_control(encode_command("specified_angle", yaw_deg=45))
    reads: list[list[Any]] = [
        [StreamChunk(5.0, frame[:7], "tcp", FROM_IDU)],
        [StreamChunk(5.1, frame[7:], "tcp", FROM_IDU)],
    ]
    sink = ListSink()
    capture = Capture(ScriptedSource(reads), [sink])
    capture.start()
    capture.wait()
    commands = [e for e in sink.events if e.topic == TOPIC_COMMAND]
    assert len(commands) == 1
    assert commands[0].fields["yaw_deg"] == 45
    assert commands[0].fields["direction"] == FROM_IDU
    assert capture.stats.bytes == 24 and capture.stats.chunks == 2


def test_tick_reports_a_stalled_message_while_running() -> None:
    now = time.time()
    first_segment = encode_attitude(pitch_deg=1.0, yaw_deg=2.0, motor_yaw_deg=3.0)[:8]
    source = ScriptedSource([[CanFrame(now, FEEDBACK_ID, first_segment)]], ends=False)
    decoder = SpyDecoder()
    sink = ListSink()
    capture = Capture(source, [sink], decoder=decoder)
    capture.start()
    try:
        wait_for(lambda: any(e.fields.get("kind") == INCOMPLETE for e in sink.events))
    finally:
        capture.stop()
        capture.join(DEADLINE_S)
    assert decoder.ticks and decoder.ticks[0] >= now
    assert capture.running is False


def test_empty_batches_keep_coming_on_a_quiet_source() -> None:
    sink = ListSink()
    capture = Capture(ScriptedSource([], ends=False), [sink], batch_interval=0.02)
    capture.start()
    try:
        wait_for(lambda: len(sink.batches) >= 5)
    finally:
        capture.stop()
        capture.join(DEADLINE_S)
    assert all(not b.items and not b.events for b in sink.batches)


class FullDisk:
    def __init__(self) -> None:
        self.calls = 0
        self.closed = 0

    def handle(self, batch: Batch) -> None:
        self.calls += 1
        if self.calls == 3:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), "/media/usb/flight.mcap")

    def close(self) -> None:
        self.closed += 1


def test_a_failing_sink_stops_the_capture_with_a_clear_error() -> None:
    frames = [[command_frame(float(i), pan_speed_dps=1.0, tilt_speed_dps=0)] for i in range(1000)]
    disk = FullDisk()
    other = ListSink()
    source = ScriptedSource(frames, ends=False)
    capture = Capture(source, [disk, other], batch_interval=0.01)
    capture.start()
    assert capture.join(DEADLINE_S)
    assert isinstance(capture.error, CaptureError)
    assert isinstance(capture.error, SourceError)  # the CLI prints it as one line, exit 1
    message = str(capture.error)
    assert message == "FullDisk failed: No space left on device: /media/usb/flight.mcap"
    assert capture.stop_reason == "error"
    assert disk.calls == 3  # not called again after failing
    assert disk.closed == 1 and other.closed == 1 and source.closed == 1
    notes = [e for e in other.events if e.topic == TOPIC_DIAGNOSTICS and e.fields["kind"] == LINK]
    assert notes and notes[-1].fields["detail"] == message


def test_a_failing_source_is_kept_as_the_error() -> None:
    class Unplugged(ScriptedSource):
        def read(self, timeout: float) -> list[Any]:
            if self.reads:
                return self.reads.pop(0)
            raise SourceError("can:pcan:PCAN_USBBUS1 failed: device removed")

    sink = ListSink()
    source = Unplugged([[command_frame(1.0, pan_speed_dps=1.0, tilt_speed_dps=0)]])
    capture = Capture(source, [sink])
    capture.start()
    capture.wait()
    assert str(capture.error) == "can:pcan:PCAN_USBBUS1 failed: device removed"
    assert sink.closed == 1
    assert sink.events[0].topic == TOPIC_COMMAND
    assert sink.events[-1].fields["kind"] == LINK
    assert sink.events[-1].fields["state"] == "failed"


def test_sink_close_failure_is_reported() -> None:
    class BadClose(ListSink):
        def close(self) -> None:
            raise OSError(errno.EIO, "Input/output error")

    capture = Capture(ScriptedSource([]), [BadClose()])
    capture.start()
    capture.wait()
    assert str(capture.error) == "BadClose failed while closing: Input/output error"


def test_bus_load_estimate() -> None:
    # 760 extended 8-byte frames in the first batch: about 10% of a 1 Mbit/s bus per 0.1 s
    assert CAN_BITS_EXTENDED + 64 == 131
    frames = [CanFrame(float(i), 0x1234567, bytes(8)) for i in range(760)]
    capture = Capture(ScriptedSource([frames], ends=False), [ListSink()], batch_interval=0.05)
    capture.start()
    try:
        wait_for(lambda: capture.stats.batches >= 2)
        stats = capture.stats
    finally:
        capture.stop()
        capture.join(DEADLINE_S)
    assert stats.frames == 760
    assert stats.frames_per_s > 0 and stats.bus_load_pct > 0
    # bits per frame are consistent with the load figure
    bits = stats.bus_load_pct / 100 * 1_000_000 / stats.frames_per_s
    assert bits == pytest.approx(131)


@posix_signals
def test_run_until_interrupted_stops_cleanly_on_sigterm() -> None:
    sink = ListSink()
    capture = Capture(ScriptedSource([], ends=False), [sink])
    timer = threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGTERM))
    timer.start()
    previous = signal.getsignal(signal.SIGTERM)
    code = run_until_interrupted(capture)
    timer.join()
    assert code == 0
    assert capture.stop_reason == "SIGTERM"
    assert sink.closed == 1 and not capture.running
    assert signal.getsignal(signal.SIGTERM) is previous


def test_run_until_interrupted_returns_1_on_error() -> None:
    class Broken(ScriptedSource):
        def read(self, timeout: float) -> list[Any]:
            raise SourceError("gone")

    capture = Capture(Broken([]), [ListSink()])
    assert run_until_interrupted(capture) == 1
    assert "gone" in str(capture.error)


def test_a_sink_added_later_gets_batches_and_is_closed() -> None:
    first, late = ListSink(), ListSink()
    capture = Capture(ScriptedSource([], ends=False), [first], batch_interval=0.01)
    capture.start()
    try:
        wait_for(lambda: len(first.batches) >= 2)
        capture.add_sink(late)
        wait_for(lambda: len(late.batches) >= 2)
    finally:
        capture.stop()
        capture.join(DEADLINE_S)
    assert late.closed == 1 and first.closed == 1


def test_start_twice_is_refused() -> None:
    capture = Capture(ScriptedSource([]), [])
    capture.start()
    with pytest.raises(RuntimeError):
        capture.start()
    capture.wait()


def test_elapsed_time_stops_when_the_capture_ends() -> None:
    import time as _time

    from analyzer.capture import Capture

    class Ends:
        description = "ends at once"

        def read(self, timeout: float) -> list[object]:
            raise EOFError

        def close(self) -> None:
            pass

    capture = Capture(Ends(), [])  # type: ignore[arg-type]
    capture.start()
    capture.wait()
    first = capture.stats.elapsed_s
    _time.sleep(0.05)
    assert capture.stats.elapsed_s == first
