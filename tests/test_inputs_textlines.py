"""Text inputs: damaged .gz files read like zcat, long lines keep line numbers, stdin is capped."""

from __future__ import annotations

import gzip
import io
import zlib
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.inputs import open_input
from analyzer.inputs.candump.reader import CandumpReader
from analyzer.inputs.stdin import StdinCandumpReader
from analyzer.inputs.textlines import MAX_LINE, TolerantGunzip, split_blocks
from analyzer.protocol.types import BAD_LINE, CanFrame, Event


def candump_lines(count: int, start: float = 1715680800.0) -> bytes:
    """``candump -L can0`` output: gimbal feedback segments 10 ms apart."""
    return b"".join(
        b"(%.6f) can0 030F0001#EB900C%010X" % (start + i * 0.01, i) + b"\n" for i in range(count)
    )


def read_all(path: Path) -> tuple[list[CanFrame], list[Event]]:
    frames: list[CanFrame] = []
    events: list[Event] = []
    with open_input(str(path)) as reader:
        for item in reader:
            (frames if isinstance(item, CanFrame) else events).append(item)  # type: ignore[arg-type]
    return frames, events


def gunzip(data: bytes) -> tuple[bytes, list[str]]:
    unzip = TolerantGunzip(io.BytesIO(data))
    return b"".join(unzip.read_blocks()), unzip.problems


def zcat_prefix(data: bytes) -> bytes:
    """What ``zcat`` writes for a cut-off file: everything that decompressed."""
    return zlib.decompressobj(31).decompress(data)


# -- gzip ------------------------------------------------------------------------------------


def test_gz_cut_off_by_power_loss_keeps_every_complete_line(tmp_path: Path) -> None:
    text = candump_lines(60_000)  # about 3 MiB of text: several of gzip's 1 MiB blocks
    packed = gzip.compress(text)
    cut = packed[: len(packed) * 2 // 3]  # the logger died while writing
    path = tmp_path / "flight.log.gz"
    path.write_bytes(cut)
    frames, events = read_all(path)
    recovered = zcat_prefix(cut)
    complete = recovered.count(b"\n")
    assert complete > 30_000
    # Every complete line decodes; the half line at the cut is one bad line.
    assert len(frames) == complete
    assert [f.data for f in frames] == [
        bytes.fromhex(line.split(b"#")[1].decode()) for line in recovered.split(b"\n")[:complete]
    ]
    damage = [e for e in events if "cut off" in e.fields["detail"]]
    assert len(damage) == 1
    assert damage[0].fields["kind"] == BAD_LINE
    assert f"after line {complete + 1}" in damage[0].fields["detail"]


def test_gz_corrupt_member_loses_only_itself(tmp_path: Path) -> None:
    # Loggers that append with ``gzip >> file`` or rotate and concatenate make several
    # members; a damaged one must not take the others with it.
    first, second, third = candump_lines(2000), candump_lines(2000, 1715680900.0), b""
    third = candump_lines(2000, 1715681000.0)
    damaged = bytearray(gzip.compress(second))
    damaged[len(damaged) // 3] ^= 0x55
    path = tmp_path / "rotated.log.gz"
    path.write_bytes(gzip.compress(first) + bytes(damaged) + gzip.compress(third))
    frames, events = read_all(path)
    times = [f.time for f in frames]
    assert times[:2000] == [f.time for f in read_text(first)]
    assert times[-2000:] == [f.time for f in read_text(third)]
    details = [e.fields["detail"] for e in events if e.fields["kind"] == BAD_LINE]
    assert any("damaged" in d or "CRC check" in d for d in details), details


def read_text(text: bytes) -> list[CanFrame]:
    reader = StdinCandumpReader(io.BytesIO(text))
    return [item for item in reader if isinstance(item, CanFrame)]


def test_gz_crc_mismatch_keeps_the_text_and_says_so() -> None:
    packed = bytearray(gzip.compress(b"(1.0) can0 123#11\n" * 10))
    packed[-8] ^= 0xFF  # the stored CRC
    text, problems = gunzip(bytes(packed))
    assert text == b"(1.0) can0 123#11\n" * 10
    assert len(problems) == 1 and "CRC check" in problems[0]


def test_gz_zero_padding_after_the_last_member_is_no_damage() -> None:
    text, problems = gunzip(gzip.compress(b"abc\n") + b"\0" * 512)
    assert (text, problems) == (b"abc\n", [])


@settings(max_examples=40, deadline=None)
@given(st.data())
def test_gz_any_cut_gives_what_decompresses_and_reports_it(data: st.DataObject) -> None:
    text = candump_lines(300)
    packed = gzip.compress(text)
    cut = data.draw(st.integers(0, len(packed)))
    out, problems = gunzip(packed[:cut])
    assert text.startswith(out)
    assert out == zcat_prefix(packed[:cut])[: len(out)]
    assert len(zcat_prefix(packed[:cut])) == len(out)
    assert bool(problems) == (0 < cut < len(packed))


@settings(max_examples=40, deadline=None)
@given(st.data())
def test_gz_flipped_bits_never_raise_and_are_reported(data: st.DataObject) -> None:
    text = candump_lines(300)
    packed = bytearray(gzip.compress(text))
    for _ in range(data.draw(st.integers(1, 4))):
        packed[data.draw(st.integers(0, len(packed) - 1))] ^= 1 << data.draw(st.integers(0, 7))
    out, problems = gunzip(bytes(packed))
    if out != text:
        assert problems


# -- line numbers and long lines -------------------------------------------------------------


def test_line_numbers_stay_right_after_a_line_over_64_kib(tmp_path: Path) -> None:
    path = tmp_path / "long.log"
    good = b"(1.000000) can0 030F0001#EB900C0000000000\n"
    path.write_bytes(good + b"(2.0) can0 123#" + b"00" * 200_000 + b"\n" + good + b"bad\n" + good)
    frames, events = read_all(path)
    assert len(frames) == 3
    lines = [e.fields["line"] for e in events]
    assert lines == [2, 4]
    assert f"longer than {MAX_LINE:,} bytes" in events[0].fields["detail"]
    with CandumpReader(str(path), block_size=4096) as small:
        items = list(small)
    assert [e.fields["line"] for e in items if isinstance(e, Event)] == [2, 4]


def test_split_blocks_holds_at_most_one_cut_line() -> None:
    blocks = iter([b"a\n" + b"x" * 100_000, b"y" * 300_000, b"z\nb\n"])
    lines = [line for chunk in split_blocks(blocks) for line in chunk]
    assert lines[0] == b"a" and lines[2] == b"b"
    assert len(lines) == 3 and len(lines[1]) == MAX_LINE + 1


def test_stdin_reads_a_huge_line_in_bounded_pieces() -> None:
    good = b"(1.000000) can0 030F0001#EB900C0000000000\n"
    huge = b"(2.0) can0 123#" + b"A" * (4 << 20)  # 4 MiB without a line end, then one
    stream = io.BytesIO(good + huge + b"\n" + good)
    reader = StdinCandumpReader(stream)
    items = list(reader)
    assert [type(i).__name__ for i in items] == ["CanFrame", "Event", "CanFrame"]
    bad = items[1]
    assert isinstance(bad, Event) and bad.fields["line"] == 2
    assert len(bad.fields.get("raw", "")) < 1000
    assert reader.stats["lines"] == 3
    assert reader.position_bytes == len(stream.getvalue())


def _corrupt_deflate(path: Path) -> Path:
    """A gzip file of candump text whose deflate stream is damaged near its start."""
    text = b"".join(b"(%d.000000) can0 00000F01#0F07%012X\n" % (i, i) for i in range(3000))
    packed = bytearray(gzip.compress(text))
    packed[40:60] = bytes(b ^ 0xFF for b in packed[40:60])  # after the 10-byte header
    with pytest.raises(zlib.error):
        gzip.decompress(bytes(packed))
    path.write_bytes(bytes(packed))
    return path


def test_a_gz_with_a_corrupt_deflate_stream_is_the_gzip_damage_diagnostic(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analyzer.cli import main

    path = _corrupt_deflate(tmp_path / "x.log.gz")
    code = main(["decode", str(path)])  # the format from the name, the content looked at
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "gzip data damaged after 0 decompressed bytes" in out


def test_a_nameless_gz_that_does_not_decompress_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analyzer.cli import main

    path = _corrupt_deflate(tmp_path / "x.gz")
    code = main(["decode", str(path)])
    _, err = capsys.readouterr()
    assert code == 2
    assert err.count("\n") == 1 and "cannot tell the format of" in err
