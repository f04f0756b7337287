"""open_input: format from name or content, clear errors, raw dumps, standard input, MCAP."""

from __future__ import annotations

import io
import os
import sys
import threading
from pathlib import Path
from typing import Any

import pytest

from analyzer.errors import UsageError
from analyzer.inputs import detect_format, open_input, sniff_format
from analyzer.inputs.stdin import StdinCandumpReader, StdinStreamReader
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.types import (
    GARBAGE,
    TOPIC_COMMAND,
    CanFrame,
    Event,
    StreamChunk,
)

LOOK_DOWN = wrap_control(encode_command("look_down"))
LOG_LINE = b"(1436509052.249713) can0 00000F01#0F07000000000000\n"


@pytest.mark.parametrize(
    ("name", "fmt"),
    [
        ("a.log", "candump"),
        ("a.LOG.gz", "candump"),
        ("a.asc", "asc"),
        ("a.blf", "blf"),
        ("a.trc", "trc"),
        ("a.csv", "csv"),
        ("a.mf4", "mf4"),
        ("a.pcap", "pcap"),
        ("a.pcapng", "pcap"),
        ("a.bin", "stream"),
        ("a.mcap", "mcap"),
    ],
)
def test_format_from_the_extension(name: str, fmt: str) -> None:
    assert detect_format(name) == fmt


@pytest.mark.parametrize(
    ("head", "fmt"),
    [
        (LOG_LINE, "candump"),
        (b"  can0  030F0001   [8]  EB 90 0C 00 00 00 00 00\n", "candump"),
        (b" (1.5)  can0  123   [2]  remote request\n", "candump"),
        (b"\xd4\xc3\xb2\xa1\x02\x00\x04\x00", "pcap"),
        (b"\x0a\x0d\x0d\x0a....", "pcap"),
        (b"\x89MCAP0\r\n", "mcap"),
        (b"LOGG\x90\x00", "blf"),
        (LOOK_DOWN, "stream"),
        (b"date Mon Jan 1 10:00:00.000 am 2024\nbase hex  timestamps absolute\n", "asc"),
        (b";$FILEVERSION=2.1\n", "trc"),
        (b"timestamp,arbitration_id,extended,remote,error,dlc,data\n", "csv"),
        (b"hello world\n", None),
    ],
)
def test_format_from_the_content(head: bytes, fmt: str | None) -> None:
    assert sniff_format(head) == fmt


def test_unknown_extension_is_sniffed(tmp_path: Path) -> None:
    path = tmp_path / "capture.txt"
    path.write_bytes(LOG_LINE * 2)
    reader = open_input(str(path))
    assert reader.format_name == "candump" and len(list(reader)) == 2


def test_unknown_content_is_a_usage_error(tmp_path: Path) -> None:
    path = tmp_path / "notes.txt"
    path.write_text("shopping list\n", encoding="utf-8")
    with pytest.raises(UsageError, match="--format"):
        open_input(str(path))


@pytest.mark.parametrize("name", ["missing.log", "missing.bin", "missing.pcap", "missing.asc"])
def test_missing_file_is_a_usage_error(tmp_path: Path, name: str) -> None:
    with pytest.raises(UsageError, match="no such file"):
        open_input(str(tmp_path / name))


def test_directory_is_a_usage_error(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="directory"):
        open_input(str(tmp_path))


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() == 0,
    reason="root reads everything (Windows: no POSIX permissions)",
)
def test_unreadable_file_is_a_usage_error(tmp_path: Path) -> None:  # pragma: no cover
    path = tmp_path / "secret.log"
    path.write_bytes(LOG_LINE)
    path.chmod(0)
    with pytest.raises(UsageError, match="permission"):
        open_input(str(path))


def test_binary_data_named_log_is_a_usage_error(tmp_path: Path) -> None:
    path = tmp_path / "image.log"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00")
    with pytest.raises(UsageError, match="not candump text"):
        open_input(str(path))


def test_unknown_format_name_lists_the_valid_ones(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="candump, asc"):
        open_input(str(tmp_path / "x"), "wav")


def test_format_aliases(tmp_path: Path) -> None:
    path = tmp_path / "dump.dat"
    path.write_bytes(LOOK_DOWN)
    assert open_input(str(path), "bin").format_name == "stream"
    assert open_input(str(path), ".stream").format_name == "stream"


# -- raw stream dumps ------------------------------------------------------------------------


def test_raw_dump_with_garbage_decodes(tmp_path: Path) -> None:
    path = tmp_path / "uart.bin"
    data = b"\x00\x13junk" + LOOK_DOWN + LOOK_DOWN[:7] + b"\xeb" + LOOK_DOWN
    path.write_bytes(data)
    reader = open_input(str(path))
    items: list[Any] = list(reader)
    assert all(isinstance(i, StreamChunk) for i in items)
    assert b"".join(i.data for i in items) == data
    assert reader.position_bytes == reader.size_bytes == len(data)
    decoder = ProtocolDecoder()
    events = [e for i in items for e in decoder.feed(i)] + decoder.close()
    assert [e.topic for e in events if e.topic == TOPIC_COMMAND] == [TOPIC_COMMAND] * 2
    assert any(e.fields.get("kind") == GARBAGE for e in events)
    stats = decoder.stats
    assert stats["bytes_fed"] == stats["bytes_framed"] + stats["bytes_discarded"] == len(data)


def test_raw_dump_in_small_chunks(tmp_path: Path) -> None:
    from analyzer.inputs.raw_stream import RawStreamReader

    path = tmp_path / "tcp.bin"
    path.write_bytes(LOOK_DOWN * 3)
    reader = RawStreamReader(str(path), direction="gs_to_idu", chunk_size=5)
    chunks: list[Any] = list(reader)
    assert len(chunks) == 15 and all(c.direction == "gs_to_idu" for c in chunks)


# -- standard input --------------------------------------------------------------------------


def test_stdin_lines_come_through_before_the_pipe_closes() -> None:
    read_fd, write_fd = os.pipe()
    with os.fdopen(read_fd, "rb") as pipe_in, os.fdopen(write_fd, "wb") as pipe_out:
        items = iter(StdinCandumpReader(pipe_in))
        got: list[Any] = []
        worker = threading.Thread(target=lambda: got.append(next(items)), daemon=True)
        pipe_out.write(LOG_LINE)
        pipe_out.flush()
        worker.start()
        worker.join(timeout=10)
        assert got and isinstance(got[0], CanFrame), "the line was not handed on while live"
        pipe_out.write(b"  can0  123   [1]  01\nbroken\n")
        pipe_out.close()
        rest = list(items)
    assert isinstance(rest[0], CanFrame) and rest[0].time > 1e9  # stamped with the clock
    assert isinstance(rest[1], Event) and rest[1].fields["line"] == 3


def test_dash_means_stdin(monkeypatch: pytest.MonkeyPatch) -> None:
    fake = io.TextIOWrapper(io.BytesIO(LOG_LINE * 2), encoding="utf-8")
    monkeypatch.setattr(sys, "stdin", fake)
    reader = open_input("-")
    assert isinstance(reader, StdinCandumpReader) and reader.source == "stdin"
    assert len(list(reader)) == 2
    assert reader.size_bytes is None


def test_dash_as_stream(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(LOOK_DOWN), encoding="utf-8"))
    reader = open_input("-", "stream")
    assert isinstance(reader, StdinStreamReader)
    chunks: list[Any] = list(reader)
    assert b"".join(c.data for c in chunks) == LOOK_DOWN


def test_dash_cannot_be_pcap() -> None:
    with pytest.raises(UsageError, match="standard input"):
        open_input("-", "pcap")


# -- MCAP ------------------------------------------------------------------------------------


def test_mcap_recording_gives_its_raw_items(tmp_path: Path) -> None:
    pytest.importorskip("analyzer.mcapio.write.sink")
    from analyzer.mcapio.write.sink import McapSink
    from analyzer.pipeline import Batch

    items: list[Any] = [
        CanFrame(1.0, 0xF01, encode_command("look_down"), channel="can0"),
        StreamChunk(2.0, LOOK_DOWN, "tcp", "gs_to_idu"),
    ]
    path = tmp_path / "rec.mcap"
    sink = McapSink(path, metadata={"source": "test"}, flush_interval=None)
    sink.handle(Batch(items=list(items), events=[]))
    sink.close()
    reader = open_input(str(path))
    assert list(reader) == items
    assert reader.position_bytes == reader.size_bytes


def test_mcap_support_missing_is_a_clear_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "rec.mcap"
    path.write_bytes(b"\x89MCAP0\r\n")
    monkeypatch.setitem(sys.modules, "analyzer.mcapio.read.reader", None)
    with pytest.raises(UsageError, match="MCAP support is not available"):
        open_input(str(path))
