"""Reading recordings back: finished files, truncated (crashed) files, damage, non-MCAP input."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from analyzer.mcapio.read.reader import McapRecording, RecordingError, read_events, read_items
from analyzer.mcapio.write.sink import McapSink
from tests.test_mcap_support import batches, decode_all, event_dicts, traffic, write_recording


def test_finished_file_gives_back_items_and_events(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    items = traffic()
    write_recording(path, items, emit_other=True)
    got = read_items(path)
    assert list(got) == items
    assert not got.recovered and got.note == ""
    events = read_events(path)
    decoded = sorted(decode_all(items, emit_other=True), key=lambda e: e.time)  # as stored
    assert event_dicts(list(events)) == event_dicts(decoded)
    assert not events.recovered


def test_metadata(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    write_recording(path)
    assert McapRecording(path).metadata()["gimbal-analyzer"]["source"] == "test:traffic"


def _live_recording(path: Path) -> list[list[object]]:
    """A recording flushed after every batch, left unfinished; returns items per flush."""
    sink = McapSink(path, metadata={"source": "t"}, flush_interval=None)
    flushed: list[list[object]] = []
    for batch in batches(traffic(2.0), size=15):
        sink.handle(batch)
        sink.flush()
        flushed.append(list(batch.items))
    # Leave the file as a killed recorder would: no summary, no footer.
    sink._file.flush()
    return flushed


def test_unfinished_file_is_recovered_up_to_the_last_flush(tmp_path: Path) -> None:
    path = tmp_path / "crashed.mcap"
    flushed = _live_recording(path)
    everything = [i for part in flushed for i in part]
    got = read_items(path)
    assert got.recovered
    assert list(got) == everything
    assert "recovered" in got.note
    recording = McapRecording(path)
    assert recording.recovered
    assert recording.metadata()["gimbal-analyzer"]["source"] == "t"


@pytest.mark.slow
def test_every_truncation_point_reads_a_prefix_without_error(tmp_path: Path) -> None:
    full = tmp_path / "full.mcap"
    flushed = _live_recording(full)
    everything = [i for part in flushed for i in part]
    data = full.read_bytes()
    cut = tmp_path / "cut.mcap"
    previous = 0
    for size in range(8, len(data), max(1, len(data) // 150)):
        cut.write_bytes(data[:size])
        got = read_items(cut)
        items = list(got)
        assert got.recovered
        assert items == everything[: len(items)]
        assert len(items) >= previous  # more file, never fewer messages
        previous = len(items)
        list(read_events(cut))  # never raises either


def test_truncated_finished_file_falls_back_to_recovery(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    items = traffic()
    write_recording(path, items)
    data = path.read_bytes()
    path.write_bytes(data[:-40])  # footer gone, data section intact
    got = read_items(path)
    assert got.recovered
    assert list(got) == items
    assert "summary" in got.note


def _middle_chunk_byte(data: bytes) -> int:
    """The middle byte of the first chunk record ending after the middle of ``data``."""
    position = 8  # after the magic
    while position + 9 <= len(data):
        opcode = data[position]
        length = int.from_bytes(data[position + 1 : position + 9], "little")
        end = position + 9 + length
        if opcode == 0x06 and end > len(data) // 2:  # Chunk
            return position + 9 + length // 2
        position = end
    raise AssertionError("no chunk after the middle")


def test_damaged_chunk_in_an_unfinished_file_is_skipped(tmp_path: Path) -> None:
    path = tmp_path / "crashed.mcap"
    flushed = _live_recording(path)
    data = bytearray(path.read_bytes())
    # Flip a byte in the middle of the chunk that holds the middle of the file (or the next
    # one): that chunk fails its CRC.
    data[_middle_chunk_byte(bytes(data))] ^= 0xFF
    path.write_bytes(bytes(data))
    recording = McapRecording(path)
    items = list(recording.items())
    assert recording.recovery is not None
    assert recording.recovery.damaged_chunks == 1
    everything = [i for part in flushed for i in part]
    assert 0 < len(items) < len(everything)
    assert all(item in everything for item in items)


def test_not_an_mcap_file(tmp_path: Path) -> None:
    path = tmp_path / "x.mcap"
    path.write_bytes(b"(1700000000.000000) can0 00000F01#0F04\n")
    with pytest.raises(RecordingError, match="not an MCAP file"):
        read_items(path)
    path.write_bytes(b"")
    with pytest.raises(RecordingError, match="empty"):
        read_events(path)
    with pytest.raises(RecordingError, match="cannot read"):
        read_items(tmp_path / "missing.mcap")


def test_replay_carries_link_and_bad_line_diagnostics(tmp_path: Path) -> None:
    from analyzer.mcapio.read.reader import read_replay
    from analyzer.protocol.decoder import ProtocolDecoder
    from analyzer.protocol.types import BAD_LINE, LINK, Event, diagnostic

    path = tmp_path / "rec.mcap"
    items = traffic(1.0)
    link = diagnostic(items[0].time, "tcp", LINK, "connected to 127.0.0.1:2000", state="connected")
    bad = diagnostic(items[5].time, "log", BAD_LINE, "line 3: not a candump line", b"xx")
    parts = batches(items, size=10)
    parts[0].events.insert(0, link)
    parts[1].events.append(bad)
    sink = McapSink(path, metadata={"source": "t"}, flush_interval=None)
    for part in parts:
        sink.handle(part)
    sink.close()
    replay = list(read_replay(path))
    assert [i for i in replay if not isinstance(i, Event)] == items
    carried = [i for i in replay if isinstance(i, Event)]
    assert [e.fields["kind"] for e in carried] == [LINK, BAD_LINE]
    # Decoding the replay gives every stored event again (order within a batch may differ).
    decoder = ProtocolDecoder()
    again: list[Event] = []
    for item in replay:
        again.extend([item] if isinstance(item, Event) else decoder.feed(item))
    again.extend(decoder.close())
    stored = list(read_events(path))

    def key(event: Event) -> str:
        return json.dumps(event.to_dict(), sort_keys=True)

    assert sorted(map(key, again)) == sorted(map(key, stored))


def test_fast_path_reads_what_the_mcap_library_reads(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    path = tmp_path / "rec.mcap"
    write_recording(path, traffic(20.0), emit_other=True, chunk_size=2048)
    ours = [(m.topic, m.log_time, m.data) for m in McapRecording(path).messages()]
    with open(path, "rb") as f:
        theirs = [
            (c.topic, m.log_time, m.data)
            for _, c, m in make_reader(f, validate_crcs=True).iter_messages(log_time_order=False)
        ]
    assert ours == theirs
    some = {"/diagnostics", "/gimbal/attitude"}
    assert [m for m in McapRecording(path).messages(topics=some)] == [
        m for m in McapRecording(path).messages() if m.topic in some
    ]


@pytest.mark.parametrize(("compression", "found_by"), [("none", "crc"), ("zstd", "decompression")])
def test_damaged_chunk_in_a_finished_file_is_skipped_and_reported(
    tmp_path: Path, compression: str, found_by: str
) -> None:
    from mcap.reader import make_reader

    path = tmp_path / "rec.mcap"
    items = traffic(10.0)
    write_recording(path, items, chunk_size=2048, compression=compression)
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    raw_id = next(c.id for c in summary.channels.values() if c.topic == "/can/frames")
    with_raw = [c for c in summary.chunk_indexes if raw_id in c.message_index_offsets]
    victim = sorted(with_raw, key=lambda c: c.chunk_start_offset)[3]
    data = bytearray(path.read_bytes())
    data[victim.chunk_start_offset + victim.chunk_length - 5] ^= 0xFF  # inside its records
    path.write_bytes(bytes(data))
    got = read_items(path)
    read = list(got)
    assert not got.recovered
    assert "damaged chunk" in got.note and found_by in got.note.lower()
    assert 0 < len(read) < len(items)
    assert all(item in items for item in read)
