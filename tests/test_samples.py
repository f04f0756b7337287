"""The sample files: made by the generator, small, and decoding to exactly the planted faults."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest

from analyzer.cli import main
from analyzer.samplegen import (
    EXPECTED_DIAGNOSTICS,
    EXPECTED_UNKNOWN_COMMANDS,
    WRITERS,
    write_samples,
)

SAMPLES = Path(__file__).resolve().parents[1] / "samples"


def decoded(capsys: pytest.CaptureFixture[str], name: str, *args: str) -> list[dict[str, object]]:
    assert main(["decode", str(SAMPLES / name), "--json", *args]) == 0
    return [json.loads(line) for line in capsys.readouterr().out.splitlines()]


def test_checked_in_samples_are_what_the_generator_makes(tmp_path: Path) -> None:
    write_samples(tmp_path)
    for name in WRITERS:
        assert (SAMPLES / name).read_bytes() == (tmp_path / name).read_bytes(), name


def test_samples_are_small_and_documented() -> None:
    assert sum(p.stat().st_size for p in SAMPLES.iterdir()) < 200_000
    readme = (SAMPLES / "README.md").read_text(encoding="utf-8")
    assert "python -m analyzer.samplegen samples/" in readme
    for name in WRITERS:
        assert name in readme


@pytest.mark.parametrize("name", list(WRITERS))
def test_samples_decode_with_only_the_planted_faults(
    capsys: pytest.CaptureFixture[str], name: str
) -> None:
    events = decoded(capsys, name)
    kinds = Counter(str(e["kind"]) for e in events if e["topic"] == "/diagnostics")
    assert dict(kinds) == EXPECTED_DIAGNOSTICS[name]
    unknown = [e for e in events if e.get("name") == "unknown"]
    assert len(unknown) == EXPECTED_UNKNOWN_COMMANDS[name]
    warned = [e for e in events if e["warnings"] and e["topic"] != "/diagnostics"]
    assert warned == unknown  # no other event carries a warning


def test_flight_log_has_every_message_kind(capsys: pytest.CaptureFixture[str]) -> None:
    events = decoded(capsys, "flight-candump.log")
    topics = {e["topic"] for e in events}
    assert topics == {
        "/gimbal/command",
        "/gimbal/attitude",
        "/gimbal/ranging",
        "/uav/gps",
        "/uav/altitude",
        "/uav/attitude",
        "/uav/text",
        "/diagnostics",
    }
    names = {e["name"] for e in events if e["topic"] == "/gimbal/command"}
    assert len(names) >= 15
    assert {e["component"] for e in events if e["topic"] == "/gimbal/command"} == {
        "gimbal",
        "dual_sensor",
    }
    others = decoded(capsys, "flight-candump.log", "--raw", "--topic", "/can/other")
    assert len(others) == 120


def test_pcap_has_both_directions(capsys: pytest.CaptureFixture[str]) -> None:
    events = decoded(capsys, "idu-tcp.pcap")
    by_direction = Counter((e["topic"], e["direction"]) for e in events)
    assert by_direction[("/gimbal/command", "gs_to_idu")] == 44
    assert by_direction[("/uav/gps", "gs_to_idu")] == 20
    assert by_direction[("/gimbal/attitude", "idu_to_gs")] == 30
    assert by_direction[("/gimbal/ranging", "idu_to_gs")] == 10


def test_summaries_of_the_samples(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["decode", str(SAMPLES / "flight-candump.log"), "--summary"]) == 0
    out = capsys.readouterr().out
    assert "38 messages, 1.90 Hz" in out and "1 of 39 CRC-protected" in out
    assert main(["decode", str(SAMPLES / "idu-tcp.pcap"), "--summary"]) == 0
    out = capsys.readouterr().out
    assert "40 messages, 2.00 Hz" in out and "0 of 84 CRC-protected" in out
