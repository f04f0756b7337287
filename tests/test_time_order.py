"""Recordings of record, convert and demo hold their messages in log-time order, chunk by chunk."""

from __future__ import annotations

from pathlib import Path

import pytest

from analyzer.cli import main
from analyzer.commands import demo
from tests.mcap_doctor import examine

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ["flight-candump.log", "idu-tcp.pcap", "uart-dump.bin"]


def assert_in_order(path: Path, compression: str = "zstd") -> None:
    diagnosis = examine(path)
    assert diagnosis.warnings == [], diagnosis.warnings[:5]  # log time going back
    assert diagnosis.errors == [], diagnosis.errors[:5]
    assert diagnosis.messages > 0
    assert diagnosis.compressions == {"" if compression == "none" else compression}


@pytest.mark.parametrize("sample", SAMPLES)
def test_convert_writes_in_time_order(
    sample: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "sample.mcap"
    assert main(["convert", str(ROOT / "samples" / sample), "-o", str(out), "-q"]) == 0
    assert_in_order(out)
    # findings are judged after their command's time; that is no input going back in time
    assert "goes back in time" not in capsys.readouterr().err


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_record_writes_in_time_order(
    compression: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "rec.mcap"
    source = f"file:{ROOT / 'samples' / 'idu-tcp.pcap'}"
    args = ["record", "--source", source, "-o", str(out), "-q", "--compression", compression]
    assert main(args) == 0
    assert_in_order(out, compression)


@pytest.mark.slow
def test_demo_writes_in_time_order(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(demo, "PLAIN_DURATION", 2.5)
    assert main(["demo", "--no-tui"]) == 0
    assert_in_order(tmp_path / "demo.mcap")


def test_convert_compression_choices(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    sample = str(ROOT / "samples" / "flight-candump.log")
    sizes = {}
    for compression in ("zstd", "lz4", "none"):
        out = tmp_path / f"{compression}.mcap"
        assert main(["convert", sample, "-o", str(out), "-q", "--compression", compression]) == 0
        assert_in_order(out, compression)
        sizes[compression] = out.stat().st_size
    assert sizes["zstd"] < sizes["lz4"] < sizes["none"]
    with pytest.raises(SystemExit):
        main(["convert", sample, "-o", str(tmp_path / "x.mcap"), "--compression", "gzip"])
    assert "invalid choice: 'gzip'" in capsys.readouterr().err


def test_convert_of_a_log_that_goes_back_in_time_stays_in_order_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a clock set back by 60 s in the middle of a log
    log = tmp_path / "back.log"
    times = [1_700_000_000 + i * 0.01 - (60 if i >= 3000 else 0) for i in range(6000)]
    log.write_text(
        "".join(f"({t:.6f}) can0 00000F01#0F04E803F4010000\n" for t in times), encoding="utf-8"
    )
    out = tmp_path / "back.mcap"
    assert main(["convert", str(log), "-o", str(out), "-q"]) == 0
    assert_in_order(out)
    assert "the input goes back in time" in capsys.readouterr().err
