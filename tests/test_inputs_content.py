"""A file read as a raw stream that is something else says what it looks like."""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

from analyzer.inputs import open_input
from analyzer.inputs.content import describe
from tests.log_makers import ardupilot_log, flight_frames, sll_pcap

ROOT = Path(__file__).resolve().parent.parent


def notes_of(path: Path) -> str:
    done = subprocess.run(
        [sys.executable, "-m", "analyzer", "decode", "--summary", "--format", "stream", str(path)],
        capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)},
        cwd=ROOT, timeout=60, check=True, encoding="utf-8",
    )  # fmt: skip
    return "\n".join(line for line in done.stderr.splitlines() if line.startswith("note:"))


def test_known_formats_read_as_a_stream_are_named_with_their_format(tmp_path: Path) -> None:
    frames = flight_frames()[:50]
    dataflash = tmp_path / "a.bin"
    dataflash.write_bytes(ardupilot_log(frames, frames[0].time - 10)[0])
    capture = sll_pcap(tmp_path / "b.bin", frames, 276)
    for path, words, fmt in (
        (dataflash, "an ArduPilot DataFlash log", "dataflash"),
        (capture, "a pcap / pcapng capture", "pcap"),
    ):
        with open_input(str(path), "stream") as reader:
            assert reader.notes == [
                f"{path.name} looks like {words}, not a raw TCP/UART stream: read it with --format {fmt}"
            ]


def test_random_bytes_are_called_probably_no_stream(tmp_path: Path) -> None:
    path = tmp_path / "noise.bin"
    path.write_bytes(random.Random(7).randbytes(5000))
    assert "noise.bin is almost all damage" in notes_of(path)


def test_text_read_as_a_stream_is_called_text(tmp_path: Path) -> None:
    path = tmp_path / "readme.bin"
    path.write_text("This is a text file, not a dump of a UART.\n" * 40, encoding="utf-8")
    assert "readme.bin looks like text, not a raw stream" in notes_of(path)
    assert describe(b"\x1f\x8b\x08\x00") == ("gzip-compressed data", None)


def summary_of(path: Path) -> tuple[str, dict[str, object]]:
    command = [sys.executable, "-m", "analyzer", "decode", "--summary", "--format", "stream"]
    runs = [
        subprocess.run(
            [*command, *extra, str(path)],
            capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)},
            cwd=ROOT, timeout=60, check=True, encoding="utf-8",
        ).stdout
        for extra in ([], ["--json"])
    ]  # fmt: skip
    return runs[0], json.loads(runs[1])


def test_a_dataflash_log_read_as_a_stream_is_no_100_percent_crc_verdict(tmp_path: Path) -> None:
    frames = flight_frames()
    path = tmp_path / "00000042.BIN"
    path.write_bytes(ardupilot_log(frames, frames[0].time - 10)[0])
    text, figures = summary_of(path)
    crc = next(line for line in text.splitlines() if "CRC errors" in line)
    assert "100.00 %" not in crc
    assert "CRC errors     not judged: the damage in 00000042.BIN is no damage" in crc
    assert crc.endswith("it is an ArduPilot DataFlash log")
    assert str(figures["not_a_stream"]).endswith("it is an ArduPilot DataFlash log")
    assert figures["crc_errors"] == 40  # the figures stay what they are, as everywhere


def test_a_real_uart_dump_keeps_its_crc_verdict() -> None:
    text, figures = summary_of(ROOT / "samples" / "uart-dump.bin")
    assert "CRC errors     1 of 27 CRC-protected messages (3.70 %)" in text
    assert figures["not_a_stream"] is None


def test_a_real_uart_dump_gets_no_such_note() -> None:
    assert notes_of(ROOT / "samples" / "uart-dump.bin") == ""


@given(head=st.binary(max_size=600))
def test_describing_any_bytes_never_raises(head: bytes) -> None:
    found = describe(head)
    assert found is None or (isinstance(found[0], str) and found[0])
