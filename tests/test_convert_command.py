"""`convert`: candump -> MCAP -> decoding the raw channel again gives the same events."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from analyzer.cli import main
from analyzer.mcapio.read.reader import McapRecording, read_events, read_items
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.types import CanFrame, Event
from tests.test_mcap_support import traffic

inputs = pytest.importorskip("analyzer.inputs")
if not hasattr(inputs, "open_input"):
    pytest.skip("analyzer.inputs.open_input is not available yet", allow_module_level=True)


def _candump(path: Path) -> list[CanFrame]:
    frames = [i for i in traffic(3.0) if isinstance(i, CanFrame)]
    with open(path, "w", encoding="utf-8") as f:
        for fr in frames:
            ident = f"{fr.can_id:08X}" if fr.extended else f"{fr.can_id:03X}"
            f.write(f"({fr.time:.6f}) {fr.channel} {ident}#{fr.data.hex().upper()}\n")
    return frames


def _decode(items: Any) -> list[dict[str, Any]]:
    decoder = ProtocolDecoder()
    events: list[Event] = []
    for item in items:
        events.extend([item] if isinstance(item, Event) else decoder.feed(item))
    events.extend(decoder.close())
    return [json.loads(json.dumps(e.to_dict())) for e in events]


def test_candump_convert_decode_round_trip(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log, out = tmp_path / "flight.log", tmp_path / "flight.mcap"
    frames = _candump(log)
    assert main(["convert", str(log), "-o", str(out)]) == 0
    assert "converted" in capsys.readouterr().err
    direct = _decode(inputs.open_input(str(log)))
    assert direct, "the candump decodes to events"
    recorded = list(read_items(out))
    assert all(isinstance(f, CanFrame) for f in recorded)
    assert len(recorded) == len(frames)
    assert [(f.can_id, f.data, f.extended) for f in recorded if isinstance(f, CanFrame)] == [
        (f.can_id, f.data, f.extended) for f in frames
    ]
    # Re-decoding the raw channel gives exactly what decoding the candump gives...
    assert _decode(recorded) == direct
    # ...and so do the events stored at conversion, with the response findings besides.
    stored = [json.loads(json.dumps(e.to_dict())) for e in read_events(out)]
    assert [e for e in stored if e["topic"] != "/analysis/response"] == direct
    assert any(e["topic"] == "/analysis/response" for e in stored)
    recording = McapRecording(out)
    assert not recording.recovered
    meta = recording.metadata()["gimbal-analyzer"]
    assert meta["source"] == f"file:{log}"
    assert not (tmp_path / "flight.mcap.partial").exists()


def test_decode_command_gives_the_same_json_for_candump_and_mcap(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("analyzer.commands.decode")
    log, out = tmp_path / "flight.log", tmp_path / "flight.mcap"
    _candump(log)
    assert main(["convert", str(log), "-o", str(out), "-q"]) == 0
    capsys.readouterr()
    assert main(["decode", str(log), "--json"]) == 0
    from_log = capsys.readouterr().out.splitlines()
    assert main(["decode", str(out), "--json"]) == 0
    from_mcap = capsys.readouterr().out.splitlines()
    assert from_log and [json.loads(x) for x in from_mcap] == [json.loads(x) for x in from_log]


def test_convert_user_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "flight.log"
    _candump(log)
    assert main(["convert", str(tmp_path / "missing.log"), "-o", str(tmp_path / "x.mcap")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["convert", str(log), "-o", str(log)]) == 2
    assert "overwrite the input" in capsys.readouterr().err
    assert main(["convert", str(log), "-o", str(tmp_path / "no" / "x.mcap")]) == 2
    assert "does not exist" in capsys.readouterr().err


@pytest.mark.parametrize("sample", ["flight-candump.log", "idu-tcp.pcap", "uart-dump.bin"])
def test_samples_decode_the_same_after_convert(
    sample: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # The candump sample ends with a damaged line: its bad_line diagnostic must come
    # back from the recording too, not only the frames.
    path = Path(__file__).resolve().parent.parent / "samples" / sample
    out = tmp_path / "sample.mcap"
    assert main(["convert", str(path), "-o", str(out), "-q"]) == 0
    capsys.readouterr()
    assert main(["decode", str(path), "--json"]) == 0
    direct = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    assert main(["decode", str(out), "--json"]) == 0
    again = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    assert direct and again == direct


def test_decode_stored_shows_the_recorded_events(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log, out = tmp_path / "flight.log", tmp_path / "flight.mcap"
    _candump(log)
    assert main(["convert", str(log), "-o", str(out), "-q"]) == 0
    capsys.readouterr()
    assert main(["decode", str(out), "--json", "--stored"]) == 0
    stored = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    assert stored == [json.loads(json.dumps(e.to_dict())) for e in read_events(out)]
    assert main(["decode", str(log), "--stored"]) == 2
    assert "--stored reads MCAP recordings" in capsys.readouterr().err
