"""The same input gives the same figures in every command: decode, convert, record, info
and the monitor."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from analyzer import PROTOCOL_NOTES
from analyzer.capture import Capture
from analyzer.cli import main
from analyzer.pipeline import Batch
from analyzer.sources.file_replay import FileReplaySource
from analyzer.tui.state import MonitorState

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = sorted(p for p in (ROOT / "samples").iterdir() if p.name != "README.md")
FIGURES = (
    "events",
    "diagnostics",
    "events_with_warnings",
    "topics",
    "diagnostics_by_kind",
    "commands",
    "feedback",
    "crc_checked",
    "crc_errors",
    "crc_error_rate",
)


class ScreenSink:
    """Folds every batch into the monitor's state, as the monitor app does."""

    def __init__(self, state: MonitorState) -> None:
        self.state = state

    def handle(self, batch: Batch) -> None:
        self.state.fold(batch)

    def close(self) -> None:
        pass


def run_json(capsys: pytest.CaptureFixture[str], *argv: str) -> dict[str, Any]:
    assert main(list(argv)) == 0
    out = capsys.readouterr().out
    data: dict[str, Any] = json.loads(out)
    return data


def figures(data: dict[str, Any]) -> dict[str, Any]:
    found: dict[str, Any] = data["figures"]
    assert set(FIGURES) <= set(found)
    return found


@pytest.mark.parametrize("sample", SAMPLES, ids=lambda p: p.name)
def test_every_command_reports_the_same_figures(
    sample: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    decoded = figures(run_json(capsys, "decode", str(sample), "--summary", "--json"))
    assert decoded["events"] > 0

    converted = tmp_path / "converted.mcap"
    assert main(["convert", str(sample), "-o", str(converted), "-q"]) == 0
    recorded = tmp_path / "recorded.mcap"
    assert main(["record", "--source", f"file:{sample}", "-o", str(recorded), "-q"]) == 0
    capsys.readouterr()
    for path in (converted, recorded):
        stored = run_json(capsys, "info", str(path), "--json")
        assert "no scan" in stored["stats_from"]
        assert figures(stored) == decoded, path.name
        scanned = run_json(capsys, "info", str(path), "--json", "--scan")
        assert figures(scanned) == decoded, f"{path.name} --scan"
        # The topic table of the recording agrees with the event counts.
        counts = {t["topic"]: t["count"] for t in stored["topics"]}
        for topic, n in decoded["topics"].items():
            assert counts[topic] == n

    # The live engine behind record, monitor and demo, read in process, with the
    # monitor's screen state fed as the monitor feeds it.
    screen = MonitorState()
    capture = Capture(FileReplaySource(str(sample)), [ScreenSink(screen)])
    capture.start()
    capture.wait()
    assert capture.error is None
    live = capture.stats
    assert live.tally.figures() == decoded
    assert live.events == decoded["events"] and live.diagnostics == decoded["diagnostics"]
    assert screen.total.events == decoded["events"]
    assert dict(screen.total.kinds) == decoded["diagnostics_by_kind"]
    feedback = sum(track["messages"] for track in decoded["feedback"].values())
    assert screen.feedback_count == feedback


def test_decode_and_info_name_the_same_longest_gap(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    sample = ROOT / "samples" / "flight-candump.log"
    assert main(["decode", str(sample), "--summary"]) == 0
    summary = capsys.readouterr().out
    recording = tmp_path / "flight.mcap"
    assert main(["convert", str(sample), "-o", str(recording), "-q"]) == 0
    capsys.readouterr()
    assert main(["info", str(recording)]) == 0
    info = capsys.readouterr().out
    gap = "longest gap 1.000 s, 2024-05-14 10:00:13.253Z .. 2024-05-14 10:00:14.253Z"
    assert gap in summary and gap in info
    assert "387 (3 diagnostics" in summary and "387 (3 diagnostics" in info


def test_recordings_cite_protocol_notes_that_exist(tmp_path: Path) -> None:
    from analyzer import PROTOCOL_DOCUMENT

    assert PROTOCOL_NOTES in PROTOCOL_DOCUMENT
    assert (ROOT / PROTOCOL_NOTES).is_file()
