"""McapSink: valid MCAP with CRCs, schemas, Foxglove views, metadata, flushing, write errors."""

from __future__ import annotations

import errno
import io
import json
from collections import Counter
from pathlib import Path
from typing import Any

import jsonschema
import pytest
from mcap.reader import NonSeekingReader, make_reader

from analyzer import PROTOCOL_DOCUMENT, __version__, output_file
from analyzer.errors import SourceError
from analyzer.mcapio.foxglove import LOG_ERROR, LOG_WARNING
from analyzer.mcapio.log_time import time_ns
from analyzer.mcapio.read.reader import McapRecording, read_items
from analyzer.mcapio.write.sink import McapSink
from analyzer.pipeline import Batch
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.schema import topic_schemas
from analyzer.protocol.types import BUS_ERROR, CanFrame, diagnostic
from tests.mcap_doctor import examine
from tests.test_mcap_support import T0, batches, decode_all, traffic, write_recording


def _messages(path: Path) -> list[tuple[Any, Any, Any]]:
    with open(path, "rb") as f:
        return list(make_reader(f, validate_crcs=True).iter_messages(log_time_order=False))


def test_recording_passes_the_mcap_reader_with_crc_validation(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    items = traffic()
    write_recording(path, items)
    events = decode_all(items)
    messages = _messages(path)
    topics = Counter(channel.topic for _, channel, _ in messages)
    assert topics["/can/frames"] == sum(isinstance(i, CanFrame) for i in items)
    assert topics["/stream/bytes"] == 2
    for topic, n in Counter(e.topic for e in events).items():
        assert topics[topic] == n
    # The sequential reader checks every chunk CRC as well.
    with open(path, "rb") as f:
        sequential = list(NonSeekingReader(f, validate_crcs=True).iter_messages())
    assert len(sequential) == len(messages)
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == len(messages)
    assert summary.chunk_indexes


def test_channels_are_json_with_valid_json_schemas(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    write_recording(path, traffic(bus_off=True), emit_other=True)
    core = topic_schemas()
    seen: set[str] = set()
    validators: dict[int, jsonschema.Draft202012Validator] = {}
    for schema, channel, message in _messages(path):
        assert channel.message_encoding == "json"
        assert schema is not None and schema.encoding == "jsonschema"
        if schema.id not in validators:
            document = json.loads(schema.data)
            jsonschema.Draft202012Validator.check_schema(document)
            if channel.topic in core:
                assert document == core[channel.topic]
            validators[schema.id] = jsonschema.Draft202012Validator(document)
        validators[schema.id].validate(json.loads(message.data))
        seen.add(channel.topic)
    assert {"/can/frames", "/stream/bytes", "/can/other", "/diagnostics/log"} <= seen
    assert {"/uav/gps/fix", "/gimbal/ranging/fix"} <= seen
    # Findings of the response analysis, the bench check's steps and what an ArduPilot
    # driver saw are not decoded from the wire: tested on their own (test_check_command
    # validates /check/steps, test_ardupilot_demo /ardupilot/*).
    not_from_the_wire = {"/analysis/response", "/check/steps", "/ardupilot/mount"}
    assert set(core) - not_from_the_wire - {"/ardupilot/targets"} <= seen


def test_log_and_publish_time_are_the_event_time(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    write_recording(path)
    for _, _, message in _messages(path):
        body = json.loads(message.data)
        if "time" in body:
            assert message.log_time == time_ns(body["time"])
        else:  # Foxglove views carry {sec, nsec} timestamps (transforms, entities: each one)
            stamps = list(_timestamps(body))
            assert stamps
            for stamp in stamps:
                assert abs(message.log_time - (stamp["sec"] * 10**9 + stamp["nsec"])) <= 1
        assert message.publish_time == message.log_time


def _timestamps(value: Any) -> Any:
    """Every "timestamp" object in a message, at any depth."""
    if isinstance(value, dict):
        if isinstance(value.get("timestamp"), dict):
            yield value["timestamp"]
        for item in value.values():
            yield from _timestamps(item)
    elif isinstance(value, list):
        for item in value:
            yield from _timestamps(item)


def test_location_fix_channels(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    write_recording(path)
    fixes: dict[str, list[dict[str, Any]]] = {}
    for schema, channel, message in _messages(path):
        if schema.name == "foxglove.LocationFix":
            fixes.setdefault(channel.topic, []).append(json.loads(message.data))
    uav, target = fixes["/uav/gps/fix"], fixes["/gimbal/ranging/fix"]
    assert uav[0]["latitude"] == pytest.approx(31.1234567)
    assert uav[0]["longitude"] == pytest.approx(118.1234567)
    assert uav[0]["frame_id"] == "uav"
    # The UAV fix carries the last reported flight altitude.
    assert uav[-1]["altitude"] == pytest.approx(506.78)
    assert target[0]["latitude"] == pytest.approx(31.12)
    assert target[0]["longitude"] == pytest.approx(118.12)
    for fix in uav + target:
        assert fix["position_covariance"] == [0.0] * 9
        assert fix["position_covariance_type"] == 0
        assert set(fix["timestamp"]) == {"sec", "nsec"}


def test_diagnostics_become_foxglove_log_messages(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    items = traffic()
    batch = batches(items)
    batch.append(Batch([], [diagnostic(T0 + 9, "can0", BUS_ERROR, "CAN error frame", b"\x01\x02")]))
    sink = McapSink(path, metadata={"source": "test"}, flush_interval=None)
    for b in batch:
        sink.handle(b)
    sink.close()
    logs = [
        json.loads(message.data)
        for schema, channel, message in _messages(path)
        if channel.topic == "/diagnostics/log"
    ]
    assert {
        schema.name for schema, channel, _ in _messages(path) if channel.topic == "/diagnostics/log"
    } == {"foxglove.Log"}
    assert len(logs) == 4
    assert logs[0]["level"] == LOG_WARNING
    assert logs[0]["message"].startswith("crc_mismatch: ")
    assert logs[0]["name"] == "can0"
    assert logs[-1]["level"] == LOG_ERROR
    assert logs[-1]["message"] == "bus_error: CAN error frame [01 02]"
    assert logs[-1]["timestamp"] == {"sec": int(T0 + 9), "nsec": 0}
    assert {"file", "line"} <= set(logs[-1])


def test_metadata_record(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    write_recording(path)
    with open(path, "rb") as f:
        metadata = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    info = metadata["gimbal-analyzer"]
    assert info["source"] == "test:traffic"
    assert info["tool_version"] == __version__
    assert info["protocol_document"] == PROTOCOL_DOCUMENT
    stats = metadata["gimbal-analyzer.stats"]
    figures = json.loads(stats["figures"])
    assert figures["diagnostics_by_kind"] == {"crc_mismatch": 2, "garbage": 1}


def test_timed_flush_puts_older_messages_on_disk(tmp_path: Path) -> None:
    path = tmp_path / "live.mcap"
    now = [0.0]
    sink = McapSink(path, metadata={"source": "t"}, flush_interval=0.5, clock=lambda: now[0])
    try:
        parts = batches(traffic(1.0), size=10)
        for batch in parts[:3]:
            sink.handle(batch)  # all within the same instant: nothing flushed yet
        assert list(read_items(path)) == []
        now[0] = 0.6
        sink.handle(parts[3])  # interval passed: chunk closed and written
        on_disk = read_items(path)
        # a provisional summary follows the data: the file as it stands is complete
        assert not on_disk.recovered
        assert list(on_disk) == [i for b in parts[:4] for i in b.items]
        assert examine(path).errors == []
        with open(path, "rb") as f:
            summary = make_reader(f).get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == sink.messages_written
        now[0] = 1.2
        sink.handle(parts[4])  # the next chunk replaces the provisional summary
        assert list(read_items(path)) == [i for b in parts[:5] for i in b.items]
        assert examine(path).errors == [] and examine(path).warnings == []
    finally:
        sink.close()
    assert not read_items(path).recovered
    assert list(read_items(path)) == [i for b in parts[:5] for i in b.items]
    diagnosis = examine(path)
    assert diagnosis.errors == [] and diagnosis.warnings == []


def test_a_large_provisional_summary_is_not_rewritten_at_every_flush(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from analyzer.mcapio.write import chunked_writer

    monkeypatch.setattr(chunked_writer, "LIVE_SUMMARY_FREE", 4096)
    path = tmp_path / "live.mcap"
    with open(path, "wb") as f:
        writer = chunked_writer.ChunkedWriter(f, live_summary=True)
        writer.start("", "test")
        channel = writer.register_channel("/t", "json", writer.register_schema("s", "", b""))
        tails = 0
        for n in range(2000):  # many tiny chunks: the summary grows past the free size
            writer.add_message(channel, n, b"{}", n, n)
            writer.flush()
            tails += writer._tail_at is not None
        writer.finish()
    assert 20 < tails < 1000  # every flush while small, then more and more rarely
    diagnosis = examine(path)
    assert diagnosis.errors == [] and diagnosis.chunks == 2000


class _FullDisk(io.FileIO):
    """A file on a disk that fills up after ``room`` bytes."""

    room = 0

    def write(self, data: Any) -> int:
        left = self.room - self.tell()
        if len(data) > left:
            if left > 0:
                super().write(bytes(data)[:left])
            raise OSError(errno.ENOSPC, "No space left on device")
        return super().write(data)


def test_disk_full_stops_with_a_clear_message_and_a_readable_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "full.mcap"
    monkeypatch.setattr(_FullDisk, "room", 40_000)
    monkeypatch.setattr(output_file, "FileIO", _FullDisk)
    now = [0.0]
    sink = McapSink(
        path, metadata={"source": "t"}, flush_interval=0.5, chunk_size=4096, clock=lambda: now[0]
    )
    written = []
    with pytest.raises(SourceError, match="No space left on device"):
        for batch in batches(traffic(20.0), size=20):
            now[0] += 1.0
            written.extend(batch.items)
            sink.handle(batch)
    assert sink.error is not None and sink.error.startswith("disk full: cannot write")
    assert f"{sink.kept_messages} messages up to" in sink.error
    sink.handle(batches(traffic(0.2))[0])  # after the failure: ignored, no second error
    sink.close()
    recording = read_items(path)
    got = list(recording)
    assert 0 < len(got) <= len(written)
    assert got == written[: len(got)]
    # every message of every chunk written completely is there (the summary did not fit)
    assert recording.recovered
    assert sum(1 for _ in McapRecording(path).messages()) == sink.kept_messages
    assert path.stat().st_size <= 40_000


def test_cannot_create_the_file(tmp_path: Path) -> None:
    with pytest.raises(output_file.OutputRefused, match="does not exist"):
        McapSink(tmp_path / "no" / "such" / "dir.mcap", metadata={})


def test_close_twice_and_write_after_close(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    sink = McapSink(path, metadata={"source": "t"})
    sink.write_item(CanFrame(T0, 0x0F01, bytes(8)))
    sink.close()
    sink.close()
    sink.write_item(CanFrame(T0 + 1, 0x0F01, bytes(8)))
    assert [m[2].log_time for m in _messages(path)] == [time_ns(T0)]


def test_odd_times_do_not_break_the_file(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    sink = McapSink(path, metadata={"source": "t"}, flush_interval=None)
    for t in (0.0, -5.0, float("nan"), 12.5):
        sink.write_item(CanFrame(t, 0x0F01, bytes(8)))
    sink.close()
    assert [m[2].log_time for m in _messages(path)] == [0, 0, 0, 12_500_000_000]


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_chunked_writer_matches_the_mcap_library_writer(tmp_path: Path, compression: str) -> None:
    from mcap.records import DataEnd, SummaryOffset
    from mcap.stream_reader import StreamReader
    from mcap.writer import CompressionType, Writer

    from analyzer.mcapio.write.chunked_writer import ChunkedWriter

    def fill(writer: Any) -> None:
        writer.start("", "test")
        schema = writer.register_schema("s", "jsonschema", b"{}")
        channels = [writer.register_channel(f"/t{i}", "json", schema, {"k": "v"}) for i in range(3)]
        writer.add_metadata("m", {"a": "b"})
        for n in range(5000):
            # channels interleaved, several messages per time stamp
            writer.add_message(channels[n % 3], 10**18 + n // 4 * 10**6, b'{"n":%d}' % n, 5, n)
            if n % 1700 == 0:
                writer.flush()
        writer.finish()

    ours, theirs = tmp_path / "ours.mcap", tmp_path / "theirs.mcap"
    with open(ours, "wb") as f:
        fill(ChunkedWriter(f, chunk_size=4096, compression=compression))
    with open(theirs, "wb") as f:
        fill(Writer(f, chunk_size=4096, compression=CompressionType[compression.upper()]))

    def content(path: Path) -> tuple[Any, ...]:
        with open(path, "rb") as f:
            reader = make_reader(f, validate_crcs=True)
            summary = reader.get_summary()
            messages = [
                (c.topic, m.log_time, m.publish_time, m.sequence, m.data)
                for _, c, m in reader.iter_messages()
            ]
            metadata = [(m.name, m.metadata) for m in reader.iter_metadata()]
        assert summary is not None and summary.statistics is not None
        stats = summary.statistics
        return (
            messages,
            metadata,
            stats.message_count,
            dict(stats.channel_message_counts),
            stats.message_start_time,
            stats.message_end_time,
            sorted((c.topic, c.metadata["k"]) for c in summary.channels.values()),
        )

    assert content(ours) == content(theirs)
    with open(ours, "rb") as stream:
        records = list(StreamReader(stream, validate_crcs=True).records)
    data_end = [r for r in records if isinstance(r, DataEnd)]
    assert data_end and data_end[0].data_section_crc != 0  # validated by the stream reader
    raw = ours.read_bytes()
    for offset in (r for r in records if isinstance(r, SummaryOffset)):
        assert raw[offset.group_start] == offset.group_opcode
    diagnosis = examine(ours)
    assert diagnosis.errors == [] and diagnosis.warnings == []
    assert diagnosis.compressions == {"" if compression == "none" else compression}


def test_chunked_writer_writes_in_log_time_order(tmp_path: Path) -> None:
    """Out-of-order input: each chunk is sorted; a message older than a chunk on disk is
    moved up to that chunk's end (its publish time keeps the original)."""
    from analyzer.mcapio.write.chunked_writer import ChunkedWriter

    path = tmp_path / "order.mcap"
    with open(path, "wb") as f:
        writer = ChunkedWriter(f, chunk_size=1 << 20)
        writer.start("", "test")
        schema = writer.register_schema("s", "jsonschema", b"{}")
        a = writer.register_channel("/a", "json", schema, {})
        for t in (30, 10, 20):
            writer.add_message(a, t, b"{}", t, t)
        b = writer.register_channel("/b", "json", schema, {})  # a channel in mid-chunk
        writer.add_message(b, 15, b"{}", 15, 1)
        writer.flush()
        writer.add_message(a, 25, b"{}", 25, 99)  # older than the chunk on disk
        writer.add_message(b, 40, b"{}", 40, 2)
        writer.finish()
    assert writer.retimed == 1
    diagnosis = examine(path)
    assert diagnosis.errors == [] and diagnosis.warnings == [] and diagnosis.chunks == 2
    with open(path, "rb") as f:
        got = [(c.topic, m.log_time, m.publish_time) for _, c, m in make_reader(f).iter_messages()]
    assert got == [
        ("/a", 10, 10), ("/b", 15, 15), ("/a", 20, 20), ("/a", 30, 30),
        ("/a", 30, 25), ("/b", 40, 40),
    ]  # fmt: skip


def test_sink_writes_a_batch_in_time_order(tmp_path: Path) -> None:
    """A batch holds its raw frames first and its events after: they are merged by time."""
    path = tmp_path / "batch.mcap"
    sink = McapSink(path, metadata={}, flush_interval=None, chunk_size=512)
    decoder = ProtocolDecoder()
    for start in (0.0, 10.0):
        batch = Batch()
        for i in range(40):
            frame = CanFrame(start + i / 10, 0x0F01, bytes.fromhex("0F04E803F4010000"))
            batch.items.append(frame)
            batch.events.extend(decoder.feed_can(frame))
        sink.handle(batch)
    sink.close()
    diagnosis = examine(path)
    assert diagnosis.errors == [] and diagnosis.warnings == [] and diagnosis.chunks > 4
    assert diagnosis.messages == 160
