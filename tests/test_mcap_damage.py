"""Damaged and hostile MCAP files: every loss reported, intact chunks kept, bounded work."""

from __future__ import annotations

import struct
import time
import tracemalloc
import zlib
from dataclasses import dataclass
from pathlib import Path

import lz4.frame
import pytest
import zstandard
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.data_stream import RecordBuilder
from mcap.records import ChunkIndex

from analyzer.cli import main
from analyzer.mcapio.read.info import recording_info
from analyzer.mcapio.read.reader import McapRecording, RecordingError, read_replay
from analyzer.mcapio.read.records import MAX_CHUNK_UNCOMPRESSED, RECORD_HEAD
from analyzer.protocol.types import INCOMPLETE, TOPIC_DIAGNOSTICS, Event
from analyzer.tally import Tally
from tests.test_mcap_support import traffic, write_recording

MAGIC = b"\x89MCAP0\r\n"
FOOTER = struct.Struct("<BQQQI")


@dataclass(frozen=True)
class ChunkAt:
    offset: int
    end: int  # end of the chunk record
    messages: tuple[tuple[int, bytes], ...]  # (log time, data) of its messages
    defines_channels: bool


def _chunks(data: bytes) -> list[ChunkAt]:
    """The chunks of an intact uncompressed recording, found by walking its records."""
    out = []
    pos = 8
    while pos + 9 <= len(data):
        opcode, length = RECORD_HEAD.unpack_from(data, pos)
        end = pos + 9 + length
        if opcode == 0x06:
            name_length = struct.unpack_from("<I", data, pos + 9 + 28)[0]
            start = pos + 9 + 32 + name_length + 8
            records = data[start:end]
            messages, defines, at = [], False, 0
            while at < len(records):
                op, size = RECORD_HEAD.unpack_from(records, at)
                if op == 0x05:
                    log_time = struct.unpack_from("<Q", records, at + 9 + 6)[0]
                    messages.append((log_time, records[at + 9 + 22 : at + 9 + size]))
                defines |= op == 0x04
                at += 9 + size
            out.append(ChunkAt(pos, end, tuple(messages), defines))
        if opcode == 0x0F:
            break
        pos = end
    return out


def _recording(tmp_path: Path, *, seconds: float = 3.0, compression: str = "none") -> Path:
    path = tmp_path / "rec.mcap"
    write_recording(path, traffic(seconds), chunk_size=1024, compression=compression)
    return path


def _summary_bounds(data: bytes) -> tuple[int, int]:
    _, _, start, _, _ = FOOTER.unpack_from(data, len(data) - 8 - 29)
    return start, len(data) - 8 - 29


def _with_summary(data: bytes, extra: bytes, *, fix_crc: bool = True) -> bytes:
    """The file with ``extra`` records put at the start of its summary (CRC made to match)."""
    start, footer_at = _summary_bounds(data)
    section = extra + data[start:footer_at]
    opcode, length, _, offsets, crc = FOOTER.unpack_from(data, footer_at)
    head = struct.pack("<BQQQ", opcode, length, start, offsets + len(extra))
    if fix_crc:
        crc = zlib.crc32(head, zlib.crc32(section))
    return data[:start] + section + head + struct.pack("<I", crc) + MAGIC


def _record(record: object) -> bytes:
    builder = RecordBuilder()
    record.write(builder)  # type: ignore[attr-defined]
    return bytes(builder.end())


def _everything(recording: McapRecording) -> list[tuple[int, bytes]]:
    return [(m.log_time, m.data) for m in recording.messages()]


# -- a flipped bit in a finished file -------------------------------------------------------------


def test_a_flipped_bit_in_a_chunk_is_reported_by_decode_and_info(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _recording(tmp_path)
    data = bytearray(path.read_bytes())
    with_frames = [c for c in _chunks(bytes(data)) if any(b'"dlc"' in m for _, m in c.messages)]
    victim = with_frames[3]
    data[victim.end - 30] ^= 0x10
    path.write_bytes(bytes(data))

    replay = read_replay(path)
    damage = [e for e in replay if isinstance(e, Event) and e.fields.get("kind") == INCOMPLETE]
    assert len(damage) == 1 and f"chunk at byte {victim.offset}" in damage[0].fields["detail"]
    assert damage[0].time == pytest.approx(victim.messages[0][0] / 1e9)

    assert main(["decode", str(path), "--summary"]) == 0
    err = capsys.readouterr().err
    assert f"damaged recording: damaged chunk at byte {victim.offset} skipped" in err

    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "finished, DAMAGED (1 unreadable part(s))" in out
    assert (
        f"damage      damaged chunk at byte {victim.offset}: the chunk fails its CRC check" in out
    )


def test_an_intact_file_is_checked_in_one_pass_and_shows_no_damage(tmp_path: Path) -> None:
    path = _recording(tmp_path, compression="zstd")
    info = recording_info(path)
    assert info.damage == [] and not info.recovered


def test_altered_statistics_are_not_believed(tmp_path: Path) -> None:
    path = _recording(tmp_path)
    data = path.read_bytes()
    truth = recording_info(path).message_count
    start, _ = _summary_bounds(data)
    at = data.index(b"\x0b", start)  # the Statistics record: message count follows its head
    forged = bytearray(data)
    forged[at + 9 : at + 17] = struct.pack("<Q", 999_999)
    path.write_bytes(bytes(forged))
    info = recording_info(path)
    assert info.message_count == truth != 999_999
    assert info.summary_damaged and "fails its CRC check" in info.recovery_note


@pytest.mark.parametrize(
    "bad",
    [
        {"format": "tally/1", "figures": "[1, 2]", "items": "{}"},
        {"format": "tally/1", "figures": '{"topics": [1]}', "items": '{"frames": "x"}'},
        {"format": "tally/1", "figures": "{}", "items": "[]"},
        {"format": "tally/1"},
        {},
    ],
)
def test_malformed_stats_metadata_falls_back_to_a_scan(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    bad: dict[str, str],
) -> None:
    good = recording_info(_recording(tmp_path))
    monkeypatch.setattr(Tally, "to_metadata", lambda self: bad)
    path = _recording(tmp_path)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "the stats record written at the end is malformed" in out
    assert recording_info(path).tally.kinds == good.tally.kinds


# -- crafted summaries ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("offset", "length"), [(2**62, 2**62), (8, 2**40), (2**40, 100), (9, 50), (0, 0)]
)
def test_a_crafted_chunk_index_is_a_reported_loss_not_a_crash(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], offset: int, length: int
) -> None:
    path = _recording(tmp_path)
    data = path.read_bytes()
    before = _everything(McapRecording(path))
    crafted = ChunkIndex(
        message_start_time=0,
        message_end_time=0,
        chunk_start_offset=offset,
        chunk_length=length,
        message_index_offsets={},
        message_index_length=0,
        compression="",
        compressed_size=length,
        uncompressed_size=length,
    )
    path.write_bytes(_with_summary(data, _record(crafted)))
    recording = McapRecording(path)
    assert not recording.recovered
    assert _everything(recording) == before
    assert len(recording.damage) == 1
    assert "outside the data section" in recording.damage[0].detail or "no chunk" in (
        recording.damage[0].detail
    )
    for args in (
        ["decode", str(path), "--summary"],
        ["info", str(path), "--scan"],
        ["convert", str(path), "-o", str(tmp_path / "out.mcap"), "-q", "--force"],
    ):
        code = main(args)
        err = capsys.readouterr().err
        assert code == 0, err
        assert "Traceback" not in err


def test_duplicated_chunk_index_records_read_each_chunk_once(tmp_path: Path) -> None:
    path = _recording(tmp_path)
    data = path.read_bytes()
    before = _everything(McapRecording(path))
    start, footer_at = _summary_bounds(data)
    section = data[start:footer_at]
    indexes, pos = [], 0
    while pos < len(section):
        opcode, length = RECORD_HEAD.unpack_from(section, pos)
        if opcode == 0x08:
            indexes.append(section[pos : pos + 9 + length])
        pos += 9 + length
    path.write_bytes(_with_summary(data, b"".join(indexes) * 200))
    started = time.perf_counter()
    recording = McapRecording(path)
    assert _everything(recording) == before
    assert recording.damage == []
    assert time.perf_counter() - started < 5


# -- hostile compression --------------------------------------------------------------------------


def _chunk_record(payload: bytes, compression: str, size: int, crc: int) -> bytes:
    name = compression.encode()
    body = struct.pack("<QQQI", 1, 2, size, crc) + struct.pack("<I", len(name)) + name
    body += struct.pack("<Q", len(payload)) + payload
    return RECORD_HEAD.pack(0x06, len(body)) + body


def _bomb(compression: str) -> bytes:
    """1 GiB of zeros: about 33 kB with zstd, about 4 MB with lz4 (16 frames of 64 MiB)."""
    zeros = bytes(64 << 20)
    if compression == "zstd":
        return zstandard.ZstdCompressor(level=3).compress(zeros) * 16
    return lz4.frame.compress(zeros) * 16


@pytest.mark.parametrize("compression", ["zstd", "lz4"])
@pytest.mark.parametrize("honest", [True, False])
def test_a_compression_bomb_is_refused_with_bounded_memory(
    tmp_path: Path, honest: bool, compression: str
) -> None:
    path = _recording(tmp_path)
    data = path.read_bytes()
    before = _everything(McapRecording(path))
    chunks = _chunks(data)
    bomb_size = 1 << 30
    bomb = _bomb(compression)
    claimed = bomb_size if honest else 4096
    record = _chunk_record(bomb, compression, claimed, 0)
    at = chunks[-1].end
    hostile = data[:at] + record  # an unfinished recording whose last chunk is the bomb
    path.write_bytes(hostile)
    tracemalloc.start()
    try:
        started = time.perf_counter()
        recording = McapRecording(path)
        got = _everything(recording)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert time.perf_counter() - started < 10
    assert peak < 3 * MAX_CHUNK_UNCOMPRESSED // 8  # far below the bomb's gigabyte
    assert got == before
    assert recording.recovered
    assert len(recording.damage) == 1
    expected = "more than the limit" if honest else "decompresses to more bytes"
    assert expected in recording.damage[0].detail


# -- unfinished files with a bad record length ----------------------------------------------------


def test_an_unfinished_file_resynchronises_after_a_bad_record_length(tmp_path: Path) -> None:
    path = _recording(tmp_path)
    data = path.read_bytes()
    chunks = _chunks(data)
    unfinished = bytearray(data[: chunks[-1].end])  # killed: no summary, no footer
    victim = [c for c in chunks if not c.defines_channels][3]
    struct.pack_into("<Q", unfinished, victim.offset + 1, 2**40)  # its record length
    path.write_bytes(bytes(unfinished))
    recording = McapRecording(path)
    got = _everything(recording)
    expected = [m for c in chunks if c is not victim for m in c.messages]
    assert got == expected
    assert recording.recovered
    assert len(recording.damage) == 1
    assert f"bytes {victim.offset}-" in recording.damage[0].detail
    assert "skipped" in recording.recovery_note


def test_a_damaged_leading_magic_does_not_hide_the_rest(tmp_path: Path) -> None:
    path = _recording(tmp_path)
    data = bytearray(path.read_bytes())
    before = _everything(McapRecording(path))
    data[3] ^= 0x01
    path.write_bytes(bytes(data))
    recording = McapRecording(path)
    assert _everything(recording) == before
    assert recording.damage and "magic" in recording.damage[0].detail
    path.write_bytes(b"(1700000000.0) can0 0F01#00\n" * 10)
    with pytest.raises(RecordingError, match="not an MCAP file"):
        McapRecording(path)


# -- the property ---------------------------------------------------------------------------------

_BASE: dict[str, bytes] = {}


def _base_file(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    if "data" not in _BASE:
        folder = tmp_path_factory.mktemp("base")
        _BASE["data"] = _recording(folder, seconds=2.0).read_bytes()
    return _BASE["data"]


@st.composite
def mutations(draw: st.DrawFn, size: int) -> list[tuple[str, int, int]]:
    kinds = st.sampled_from(["flip", "truncate", "duplicate_index", "crafted_index", "zero"])
    return draw(
        st.lists(
            st.tuples(kinds, st.integers(0, size - 1), st.integers(0, 2**64 - 1)),
            min_size=1,
            max_size=6,
        )
    )


def _mutate(data: bytes, plan: list[tuple[str, int, int]]) -> tuple[bytes, set[int]]:
    """Apply the plan; returns the new bytes and the byte positions that were changed."""
    out = bytearray(data)
    touched: set[int] = set()
    for kind, position, value in plan:
        if not out:
            break
        position %= len(out)
        if kind == "flip":
            out[position] ^= 1 << (value % 8)
            touched.add(position)
        elif kind == "zero":
            for i in range(position, min(len(out), position + value % 64)):
                out[i] = 0
                touched.add(i)
        elif kind == "truncate":
            touched.update(range(position, len(out)))
            del out[position:]
        elif len(out) > 64 and out.endswith(MAGIC):
            try:
                start, footer_at = _summary_bounds(bytes(out))
            except struct.error:
                continue
            if not 0 < start < footer_at:
                continue
            if kind == "duplicate_index":
                extra = bytes(out[start:footer_at])
            else:
                extra = _record(
                    ChunkIndex(
                        message_start_time=0,
                        message_end_time=0,
                        chunk_start_offset=value % (2**63),
                        chunk_length=(value >> 7) % (2**63),
                        message_index_offsets={1: value % 1000},
                        message_index_length=0,
                        compression="",
                        compressed_size=0,
                        uncompressed_size=0,
                    )
                )
            out = bytearray(_with_summary(bytes(out), extra))
            touched.update(range(start, len(out)))  # the summary: not a chunk
    return bytes(out), touched


@pytest.mark.slow
@settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_mutated_recordings_keep_intact_chunks_and_report_every_loss(
    tmp_path_factory: pytest.TempPathFactory, data: st.DataObject
) -> None:
    original = _base_file(tmp_path_factory)
    chunks = _chunks(original)
    plan = data.draw(mutations(len(original)))
    mutated, _ = _mutate(original, plan)
    common = min(len(original), len(mutated))
    touched = {i for i in range(common) if original[i] != mutated[i]}
    touched.update(range(common, len(original)))  # cut off
    path = tmp_path_factory.mktemp("mutated") / "m.mcap"
    path.write_bytes(mutated)
    tracemalloc.start()
    started = time.perf_counter()
    try:
        try:
            recording = McapRecording(path)
        except RecordingError:
            assert mutated[:8] != MAGIC or len(mutated) < 8  # only an unrecognisable file
            return
        got = _everything(recording)
        recording.verify()
        info = recording_info(path)
        events = list(read_replay(path))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert time.perf_counter() - started < 10
    assert peak < 64 << 20
    intact = [c for c in chunks if not touched & set(range(c.offset, c.end))]
    channels_kept = all(c in intact for c in chunks if c.defines_channels)
    expected = [m for c in chunks for m in c.messages]
    lost = len(expected) - len(got)
    reported = bool(recording.damage) or bool(recording.recovery_note)
    if channels_kept:
        got_set = set(got)
        for chunk in intact:  # every intact chunk still decodes
            assert all(m in got_set for m in chunk.messages), chunk.offset
    if lost > 0 or len(intact) < len(chunks):
        assert reported, plan  # every loss is reported
        assert info.damage or info.recovered or info.recovery_note
        damaged_parts = [
            e
            for e in events
            if isinstance(e, Event)
            and e.topic == TOPIC_DIAGNOSTICS
            and e.fields.get("kind") == INCOMPLETE
        ]
        assert damaged_parts or not got or recording.recovered
