"""The writer's hold-back: late messages keep their own log time across live flushes."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import NonSeekingReader, make_reader

from analyzer import output_file
from analyzer.errors import SourceError
from analyzer.mcapio.channels import STATS_METADATA_NAME
from analyzer.mcapio.read.reader import McapRecording, read_items
from analyzer.mcapio.write.chunked_writer import ChunkedWriter
from analyzer.mcapio.write.failure import keep_complete_chunks
from analyzer.mcapio.write.sink import McapSink
from analyzer.protocol.types import CanFrame
from tests.mcap_doctor import examine
from tests.test_mcap_writer import _FullDisk  # a disk that fills up after `room` bytes

S = 1_000_000_000  # ns
T0 = 1_700_000_000 * S
HOLD_BACK = S  # one second


class _Recorder:
    """A live writer with two channels: telemetry on time, video that reaches it late."""

    def __init__(self, path: Path, *, hold_back: int = HOLD_BACK, chunk_size: int = 1 << 20):
        self.file = path.open("wb")
        self.writer = ChunkedWriter(
            self.file, chunk_size=chunk_size, live_summary=True, hold_back=hold_back
        )
        self.writer.start("", "test")
        schema = self.writer.register_schema("t", "jsonschema", b"{}")
        self.channels = {
            "/telemetry": self.writer.register_channel("/telemetry", "json", schema),
            "/camera/main": self.writer.register_channel("/camera/main", "json", schema),
        }
        self.sequence = 0

    def add(self, topic: str, t: int, size: int = 0) -> None:
        """A message whose own time ``t`` is in its data and its publish time."""
        self.sequence += 1
        data = json.dumps({"t": t, "pad": "x" * size}).encode()
        self.writer.add_message(self.channels[topic], t, data, t, self.sequence)

    def finish(self) -> None:
        self.writer.finish()
        self.file.close()


def _library_messages(path: Path) -> list[tuple[str, int, int, int]]:
    """(topic, log time, publish time, own time) in file order, read by the mcap library."""
    with path.open("rb") as f:
        found = make_reader(f, validate_crcs=True).iter_messages(log_time_order=False)
        return [(c.topic, m.log_time, m.publish_time, json.loads(m.data)["t"]) for _, c, m in found]


def _our_messages(path: Path) -> list[tuple[str, int, int]]:
    """(topic, log time, own time) in file order, read by the project's reader."""
    return [(m.topic, m.log_time, json.loads(m.data)["t"]) for m in McapRecording(path).messages()]


def test_a_frame_late_by_less_than_the_hold_back_keeps_its_log_time_across_flushes(
    tmp_path: Path,
) -> None:
    path = tmp_path / "late.mcap"
    recorder = _Recorder(path)
    late = 3 * S // 10  # each frame reaches the writer 0.3 s after the telemetry of its time
    frames = iter(range(T0, T0 + 6 * S, S // 30))
    frame = next(frames)
    for n in range(600):  # telemetry at 100 Hz for 6 s, a flush every half second
        now = T0 + n * S // 100
        recorder.add("/telemetry", now)
        while frame + late <= now:
            recorder.add("/camera/main", frame)
            frame = next(frames)
        if n % 50 == 49:
            recorder.writer.flush()
    recorder.finish()
    assert recorder.writer.retimed == 0
    diagnosis = examine(path)
    assert diagnosis.errors == [] and diagnosis.warnings == []  # in log-time order
    assert diagnosis.chunks >= 10  # the flushes wrote chunks all along
    found = _library_messages(path)
    assert len(found) == 600 + 171  # frames up to 5.7 s: later ones never came
    assert all(log == publish == own for _, log, publish, own in found)
    assert [log for _, log, _, _ in found] == sorted(log for _, log, _, _ in found)
    assert _our_messages(path) == [(topic, log, own) for topic, log, _, own in found]


def test_a_frame_later_than_the_hold_back_is_moved_up_as_without_one(tmp_path: Path) -> None:
    path = tmp_path / "later.mcap"
    recorder = _Recorder(path)
    for n in range(40):  # telemetry at 10 Hz for 4 s
        recorder.add("/telemetry", T0 + n * S // 10)
        if n % 5 == 4:
            recorder.writer.flush()
    on_disk_until = recorder.writer.end_time
    assert on_disk_until == T0 + 29 * S // 10  # 3.9 s written, less the last second
    recorder.add("/camera/main", T0 + 2 * S)  # 1.9 s late: older than a chunk on disk
    recorder.add("/camera/main", T0 + 3 * S)  # 0.9 s late: still held open
    recorder.finish()
    assert recorder.writer.retimed == 1
    assert examine(path).warnings == []
    camera = [m for m in _library_messages(path) if m[0] == "/camera/main"]
    assert camera == [
        ("/camera/main", on_disk_until, T0 + 2 * S, T0 + 2 * S),  # log time moved up
        ("/camera/main", T0 + 3 * S, T0 + 3 * S, T0 + 3 * S),
    ]


def test_a_killed_recorder_leaves_an_indexed_file_of_what_is_older_than_the_hold_back(
    tmp_path: Path,
) -> None:
    path = tmp_path / "live.mcap"
    recorder = _Recorder(path)
    for n in range(30):  # 3 s of telemetry at 10 Hz
        recorder.add("/telemetry", T0 + n * S // 10)
    recorder.writer.flush()
    killed = tmp_path / "killed.mcap"
    shutil.copyfile(path, killed)  # the file as a kill -9 leaves it
    with killed.open("rb") as f:
        summary = make_reader(f).get_summary()  # the provisional summary: indexed
    assert summary is not None and summary.statistics is not None
    kept = [own for _, _, _, own in _library_messages(killed)]
    assert kept == [T0 + n * S // 10 for n in range(20)]  # up to 1 s before the newest
    assert not McapRecording(killed).recovered
    assert [own for _, _, own in _our_messages(killed)] == kept
    recorder.add("/camera/main", T0 + 25 * S // 10)  # late, within the hold-back
    recorder.finish()
    found = _library_messages(path)
    assert len(found) == 31 and all(log == own for _, log, _, own in found)
    assert examine(path).warnings == [] and examine(path).errors == []
    with path.open("rb") as f:
        assert len(list(NonSeekingReader(f, validate_crcs=True).iter_messages())) == 31


def test_large_messages_fill_chunks_by_size_and_late_ones_still_keep_their_time(
    tmp_path: Path,
) -> None:
    """A stream that fills a chunk between flushes (a 1080p camera) is held back too."""
    path = tmp_path / "big.mcap"
    recorder = _Recorder(path, chunk_size=64 * 1024)
    frames = list(range(T0, T0 + 4 * S, S // 30))
    for i, t in enumerate(frames):
        recorder.add("/camera/main", t, size=8000)  # 8 kB frames: a chunk every 8 frames
        if i >= 15:
            recorder.add("/telemetry", frames[i - 15])  # half a second behind the video
    recorder.finish()
    assert recorder.writer.retimed == 0
    diagnosis = examine(path)
    # closed by size (there is no flush), each chunk at least as large as what is held
    assert diagnosis.errors == [] and diagnosis.warnings == [] and diagnosis.chunks >= 3
    found = _library_messages(path)
    assert len(found) == 2 * len(frames) - 15
    assert all(log == own for _, log, _, own in found)


def test_the_sink_writes_held_back_messages_when_nothing_else_comes(tmp_path: Path) -> None:
    path = tmp_path / "quiet.mcap"
    now = [0.0]
    sink = McapSink(path, metadata={}, flush_interval=0.5, clock=lambda: now[0], hold_back=1.0)
    try:
        for n in range(20):  # 2 s of frames, a flush every half second
            now[0] = n / 10
            sink.write_item(CanFrame(T0 / S + n / 10, 0x0F01, bytes(8)))
            sink.flush()
        assert McapRecording(path).summary().statistics.message_count == 10  # 1 s held back
        now[0] = 3.0
        sink.flush()  # nothing came since: the held ones go to disk
        assert McapRecording(path).summary().statistics.message_count == 20
    finally:
        sink.close()
    assert sum(1 for _ in McapRecording(path).messages()) == 20


def test_a_full_disk_keeps_every_complete_chunk_in_order(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "full.mcap"
    monkeypatch.setattr(_FullDisk, "room", 60_000)
    monkeypatch.setattr(output_file, "FileIO", _FullDisk)
    now = [0.0]
    sink = McapSink(
        path,
        metadata={},
        flush_interval=0.5,
        chunk_size=16 * 1024,
        compression="none",
        clock=lambda: now[0],
        hold_back=1.0,
    )
    written: list[CanFrame] = []
    with pytest.raises(SourceError, match="No space left on device"):
        for n in range(10_000):
            now[0] = n / 100
            written.append(CanFrame(T0 / S + n / 100, 0x0F01, n.to_bytes(8, "little")))
            sink.write_item(written[-1])
            if n % 50 == 49:
                sink.flush()
    sink.close()
    assert sink.error is not None and f"{sink.kept_messages} messages up to" in sink.error
    assert path.stat().st_size <= 60_000
    got = list(read_items(path))
    assert 0 < len(got) == sink.kept_messages < len(written)
    assert got == written[: len(got)]  # the first ones, none lost between


def test_when_a_chunk_does_not_fit_the_messages_held_back_from_it_are_still_tried(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "full.mcap"
    monkeypatch.setattr(_FullDisk, "room", 1 << 30)
    with _FullDisk(path, "w") as f:
        writer = ChunkedWriter(f, compression="none", live_summary=True, hold_back=HOLD_BACK)
        writer.start("", "test")
        channel = writer.register_channel("/t", "json", writer.register_schema("t", "", b""))
        writer.add_message(channel, T0, b'{"big": "' + b"x" * 20_000 + b'"}', T0, 1)
        writer.add_message(channel, T0 + 2 * S, b"{}", T0 + 2 * S, 2)  # held back
        monkeypatch.setattr(_FullDisk, "room", writer.position + 5000)
        with pytest.raises(OSError):
            writer.flush()  # the chunk of the big message fails after 5000 bytes
        keep_complete_chunks(writer, f.fileno(), lambda: {"frames": "2"})
    with path.open("rb") as f:
        found = [m.log_time for _, _, m in make_reader(f, validate_crcs=True).iter_messages()]
    assert found == [T0 + 2 * S]  # what fitted in the space the failed chunk freed
    assert McapRecording(path).metadata()[STATS_METADATA_NAME] == {"frames": "2"}


@st.composite
def _arrivals(draw: st.DrawFn) -> tuple[list[tuple[str, int, int]], list[bool], int]:
    """Messages (topic, own time, pad) in an order where each comes less than the hold-back
    after the newest before it (at its time plus a delay under the hold-back; often each
    topic's in their order), with a flush after some of them, and a chunk size."""
    count = draw(st.integers(1, 120))
    steps = draw(st.lists(st.integers(0, S // 5), min_size=count, max_size=count))
    delays = draw(st.lists(st.integers(0, HOLD_BACK - 1), min_size=count, max_size=count))
    topics = draw(st.lists(st.sampled_from(["/telemetry", "/camera/main"]), min_size=count))
    pads = draw(st.lists(st.integers(0, 600), min_size=count, max_size=count))
    times, t = [], T0
    for step in steps:
        t += step
        times.append(t)
    topic = [topics[i % len(topics)] for i in range(count)]
    # a message reaches the writer at its own time plus its delay (less than the hold-back);
    # often each topic's messages come in their order, as a camera's frames do
    arrival = [times[i] + delays[i] for i in range(count)]
    if draw(st.booleans()):
        last: dict[str, int] = {}
        for i in range(count):
            arrival[i] = last[topic[i]] = max(arrival[i], last.get(topic[i], 0))
    order = sorted(range(count), key=lambda i: (arrival[i], i))
    messages = [(topic[i], times[i], pads[i]) for i in order]
    flushes = draw(st.lists(st.booleans(), min_size=count, max_size=count))
    chunk_size = draw(st.sampled_from([1024, 4096, 1 << 20]))
    return messages, flushes, chunk_size


@pytest.mark.slow
@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(case=_arrivals())
def test_any_arrival_within_the_hold_back_gives_each_message_its_own_log_time(
    tmp_path: Path, case: tuple[list[tuple[str, int, int]], list[bool], int]
) -> None:
    messages, flushes, chunk_size = case
    path = tmp_path / "any.mcap"
    recorder = _Recorder(path, chunk_size=chunk_size)
    for (topic, t, pad), flush in zip(messages, flushes, strict=True):
        recorder.add(topic, t, pad)
        if flush:
            recorder.writer.flush()
    recorder.finish()
    assert recorder.writer.retimed == 0
    diagnosis = examine(path)
    assert diagnosis.errors == [] and diagnosis.warnings == []  # in order, chunk by chunk
    found = _library_messages(path)
    assert all(log == publish == own for _, log, publish, own in found)
    assert sorted((own, topic) for topic, _, _, own in found) == sorted(
        (t, topic) for topic, t, _ in messages
    )
    assert [log for _, log, _, _ in found] == sorted(log for _, log, _, _ in found)
    assert _our_messages(path) == [(topic, log, own) for topic, log, _, own in found]
