"""`info`: counts, rates, diagnostics, feedback gaps; no scan of finished files; recovered files."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest

from analyzer.cli import main
from analyzer.mcapio.read.info import recording_info
from analyzer.mcapio.write.sink import McapSink
from tests.test_mcap_support import T0, batches, decode_all, traffic, write_recording


def test_finished_file_is_summarised_without_scanning(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    items = traffic(6.0, gap_after=2.0, bus_off=True)
    write_recording(path, items)
    info = recording_info(path)
    assert not info.recovered
    assert info.scanned_messages == 0
    assert info.counts_from == "summary"
    assert "no scan" in info.stats_from
    counts = {t.topic: t.count for t in info.topics}
    events = decode_all(items)
    for topic, n in Counter(e.topic for e in events).items():
        assert counts[topic] == n
    assert counts["/can/frames"] + counts["/stream/bytes"] == len(items)
    assert info.start_ns == round(T0 * 1e9)
    assert info.duration_s == pytest.approx(items[-1].time - T0, abs=1e-6)
    rates = {t.topic: t.rate_hz for t in info.topics}
    assert rates["/gimbal/command"] == pytest.approx(counts["/gimbal/command"] / info.duration_s)
    assert info.tally.kinds == Counter({"crc_mismatch": 2, "garbage": 1, "bus_error": 2})
    # The adapter went bus-off and was restarted: the record says so without a scan.
    bus = info.tally.bus.figures()
    assert (bus["worst_state"], bus["worst_channel"]) == ("bus-off", "can0")
    assert bus["channels"]["can0"]["state"] == "error-active"
    assert bus["classes"] == {"bus-off": 1, "restarted-after-bus-off": 1}
    # Feedback every 0.25 s (attitude and ranging), none for 2 s after t=2: the longest
    # gap is 2.25 s, from the ranging message at 1.75 s to the attitude at 4.0 s.
    (track,) = info.tally.feedback.values()
    assert track.longest_gap == pytest.approx(2.25, abs=0.01)
    assert track.gap_start == pytest.approx(T0 + 1.75 + 0.013, abs=0.01)
    assert track.gaps_over_threshold == 1
    # A scan of the recorded frames and events gives the same figures.
    scanned = recording_info(path, scan=True)
    assert scanned.scanned_messages > 0
    assert scanned.tally.figures() == info.tally.figures()
    assert scanned.tally.items() == info.tally.items()


def test_recovered_file_is_scanned_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "crashed.mcap"
    sink = McapSink(path, metadata={"source": "can:virtual:test"}, flush_interval=None)
    for batch in batches(traffic(3.0)):
        sink.handle(batch)
    sink.flush()
    sink._file.flush()  # a killed recorder: no summary, no footer
    info = recording_info(path)
    assert info.recovered
    assert "recovered" in info.recovery_note
    assert info.message_count > 0
    (track,) = info.tally.feedback.values()
    assert track.count == 12  # attitude and ranging, each every 0.5 s
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "RECOVERED" in out
    assert "can:virtual:test" in out
    assert "full sequential scan" in out


def test_info_command_text_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "rec.mcap"
    write_recording(path, traffic(bus_off=True))
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "finished" in out
    assert "/gimbal/command" in out and "foxglove.LocationFix" in out
    assert "crc_mismatch" in out
    assert "longest gap" in out
    assert "2023-11-14 22:13:20.000Z" in out
    assert "2 error frames, worst bus-off at 2023-11-14 22:13:24.300Z, now error-active" in out
    assert "can0 went bus-off at 2023-11-14 22:13:24.300Z and came back" in out
    assert main(["info", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["recovered"] is False
    assert data["diagnostics_by_kind"] == {"crc_mismatch": 2, "garbage": 1, "bus_error": 2}
    assert data["figures"]["bus"]["worst_state"] == "bus-off"
    assert data["figures"]["feedback"]["can0"]["messages"] == 16  # attitude and ranging in 4 s
    assert data["figures"]["topics"]["/gimbal/attitude"] == 8


def test_info_on_a_bad_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "x.mcap"
    path.write_text("not a recording\n", encoding="utf-8")
    assert main(["info", str(path)]) == 2
    assert "not an MCAP file" in capsys.readouterr().err
