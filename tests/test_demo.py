"""`gimbal-analyzer demo` off a terminal: ends by itself, prints decoded lines, writes an MCAP."""

from __future__ import annotations

import importlib.util
import json
from collections import Counter
from pathlib import Path

import pytest

from analyzer.cli import main
from analyzer.commands import demo
from analyzer.sim.ground import DEMO_SCRIPT, GroundScript

HAVE_MCAP_SINK = importlib.util.find_spec("analyzer.mcapio.write.sink") is not None


def topics_in(path: Path) -> Counter[str]:
    from mcap.reader import make_reader

    with path.open("rb") as stream:
        reader = make_reader(stream, validate_crcs=True)
        return Counter(channel.topic for _, channel, _ in reader.iter_messages())


@pytest.mark.slow
@pytest.mark.skipif(
    not HAVE_MCAP_SINK, reason="analyzer.mcapio.write.sink (the MCAP sink) is absent"
)
def test_demo_off_a_terminal_ends_by_itself_and_records_demo_mcap(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(demo, "PLAIN_DURATION", 3.0)  # instead of 10 s, to keep the test short
    assert main(["demo"]) == 0  # no --no-tui: stdout is not a terminal here
    out = capsys.readouterr().out
    assert out.startswith("demo: simulated gimbal + UAV and a scripted ground station")
    assert "/gimbal/command" in out and "gimbal_control" in out
    assert "/gimbal/attitude" in out
    assert "recorded to demo.mcap" in out
    topics = topics_in(tmp_path / "demo.mcap")
    for topic in ("/can/frames", "/gimbal/command", "/gimbal/attitude", "/uav/gps"):
        assert topics[topic] > 0, topics
    assert topics["/gimbal/attitude"] >= 4


@pytest.mark.slow
@pytest.mark.skipif(
    not HAVE_MCAP_SINK, reason="analyzer.mcapio.write.sink (the MCAP sink) is absent"
)
def test_demo_clean_has_no_fault_diagnostics(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "clean.mcap"
    assert main(["demo", "--no-tui", "--clean", "--duration", "2", "-o", str(path)]) == 0
    out = capsys.readouterr().out
    assert "faults: none" in out
    for kind in ("crc_mismatch", "incomplete", "duplicate"):
        assert kind not in out
    assert topics_in(path)["/gimbal/command"] > 0


def test_demo_output_directory_must_exist(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["demo", "--no-tui", "-o", str(tmp_path / "missing" / "x.mcap")])
    assert code == 2  # a refused output, like an existing one
    assert "does not exist" in capsys.readouterr().err


def test_demo_script_moves_the_gimbal_early_and_loops() -> None:
    script = GroundScript()
    sent = [script.due(t / 100) for t in range(0, 3100)]
    first = [data for batch in sent[:1000] for data in batch]
    assert first[0][:2] == bytes([0x0F, 0x02])  # forward
    gimbal_control = [d for d in first if d[1] == 0x04]
    assert len(gimbal_control) > 40  # repeated every 50 ms while a move lasts
    names = {s.name for s in DEMO_SCRIPT}
    assert {"gimbal_control", "specified_angle", "tracking", "zoom", "look_down"} <= names
    second_round = [d for batch in sent[1500:2500] for d in batch]
    assert len(second_round) == len([d for batch in sent[:1000] for d in batch])


def test_demo_replaces_demo_mcap_but_no_other_file_without_force(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    precious = tmp_path / "flight.mcap"
    precious.write_bytes(b"keep me")
    assert main(["demo", "--no-tui", "-o", str(precious)]) == 2
    assert "use --force" in capsys.readouterr().err
    assert precious.read_bytes() == b"keep me"


@pytest.mark.slow
@pytest.mark.skipif(
    not HAVE_MCAP_SINK, reason="analyzer.mcapio.write.sink (the MCAP sink) is absent"
)
def test_demo_with_a_heading_is_judged_from_north_without_a_false_stopped_short(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analyzer.mcapio.read.reader import read_events

    path = tmp_path / "heading.mcap"
    args = ["demo", "--no-tui", "--clean", "--heading", "30", "--duration", "6", "-o", str(path)]
    assert main(args) == 0
    capsys.readouterr()
    events = list(read_events(path))
    offsets = {
        round((e.fields["yaw_deg"] - e.fields["motor_yaw_deg"]) % 360, 1)
        for e in events
        if e.topic == "/gimbal/attitude"
    }
    assert offsets == {30.0}  # psi = heading + motor yaw, as on a real aircraft
    assert main(["analyze", str(path), "--json"]) == 0
    found = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert not [f for f in found if "stopped short" in f["detail"] or "other way" in f["detail"]]
    yaw = next(f for f in found if f["check"] == "target" and f.get("axis") == "yaw")
    assert yaw["target_deg"] == 90 and yaw["verdict"] == "obeyed", yaw["detail"]
    assert (yaw["yaw_reference"], yaw["reference_reason"]) == ("north", "FF13 present")
    recorded = [e.fields for e in events if e.topic == "/analysis/response"]
    assert {f.get("reference_reason") for f in recorded if f.get("axis") == "yaw"} == {
        "FF13 present"
    }
    # The recording keeps the simulator's options that made it; info shows them.
    assert main(["info", str(path)]) == 0
    shown = capsys.readouterr().out.splitlines()
    assert "simulator   --clean --heading 30" in shown
    assert "  faults    none" in shown and "  heading   30 deg from north" in shown
    assert "  gimbal    obeys" in shown


def test_demo_help_names_only_what_exists(capsys: pytest.CaptureFixture[str]) -> None:
    """Every option its help mentions is one of demo's, every command one the tool has."""
    import re

    from analyzer.cli import COMMANDS, build_parser

    with pytest.raises(SystemExit):
        main(["demo", "--help"])
    text = capsys.readouterr().out
    parser = build_parser("demo").commands["demo"]
    options = {o for a in parser._actions for o in a.option_strings}
    assert set(re.findall(r"(?<![\w-])--[a-z][a-z-]+", text)) <= options
    for line in re.findall(r"^  (\S+) \S+\.mcap", text, re.MULTILINE):
        assert line == "gimbal-analyzer"
    assert set(re.findall(r"gimbal-analyzer (\w+)", text)) <= set(COMMANDS)


@pytest.mark.slow
@pytest.mark.skipif(
    not HAVE_MCAP_SINK, reason="analyzer.mcapio.write.sink (the MCAP sink) is absent"
)
def test_demo_metadata_repeats_the_fault_and_behaviour_options(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analyzer.mcapio.read.info import recording_info

    path = tmp_path / "faulty.mcap"
    args = ["demo", "--no-tui", "--duration", "1", "-o", str(path), "--drop", "0.1"]
    assert main([*args, "--seed", "3", "--ignore", "tracking", "--sluggish", "0.5"]) == 0
    capsys.readouterr()
    meta = recording_info(str(path)).metadata
    assert meta["simulator_options"] == (
        "--drop 0.1 --corrupt 0.02 --duplicate 0.02 --delay 0.02 --seed 3 "
        "--sluggish 0.5 --ignore tracking"
    )
    assert meta["simulator_faults"] == "drop 10%, corrupt 2%, duplicate 2%, delay 2% (seed 3)"
    assert meta["simulator_gimbal"] == "moves at 50% of the asked speed; ignores tracking"
    assert meta["simulator_heading"] == "ahead along the orbit"


def test_the_stick_script_changes_the_speeds_in_every_command_and_centres_with_zeros() -> None:
    from analyzer.protocol.codec import decode_command
    from analyzer.sim.ground import pilot_script

    script = GroundScript(pilot_script(), period=None)
    sent = [(t / 100, data) for t in range(0, 500) for data in script.due(t / 100)]
    speeds = [(t, decode_command(data)[0]) for t, data in sent if data[1] == 0x04]
    moving = [(t, f["pan_speed_dps"], f["tilt_speed_dps"]) for t, f in speeds]
    tilting = [v for t, _, v in moving if 0.6 < t < 1.9]
    assert len(tilting) > 20 and len(set(tilting)) > 0.8 * len(tilting)  # a hand, a reading
    assert min(tilting) < -20  # the stick's peak above the fixed step's -20
    # after each movement the stick is centred: zeros for a moment, then nothing
    assert any(p == 0 and v == 0 for t, p, v in moving if 3.4 <= t <= 3.55)
    assert not [t for t, _, _ in moving if 3.6 < t < 5.0]


@pytest.mark.slow
@pytest.mark.skipif(
    not HAVE_MCAP_SINK, reason="analyzer.mcapio.write.sink (the MCAP sink) is absent"
)
def test_demo_stick_records_the_option_and_each_movement_is_one_finding(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "stick.mcap"
    args = ["demo", "--no-tui", "--clean", "--stick", "--duration", "4.5", "-o", str(path)]
    assert main([*args, "--sluggish", "0.4"]) == 0
    capsys.readouterr()
    assert main(["info", str(path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert "--stick" in info["metadata"]["simulator_options"]
    assert main(["analyze", str(path), "--json"]) == 0
    found = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    rates = [f for f in found if f["command"] == "gimbal_control" and f["check"] == "rate"]
    # tilt, a moment centred (zeros), then pan: two movements. The tilt is judged
    # sluggish; the pan (1.2 s) is followed 0.2 s after it by a specified_angle and the
    # run ends 1.1 s after it, both within the lag a gimbal may have: it is not judged
    assert [r["verdict"] for r in rates] == ["partial", "unknown"]
    assert rates[0]["tilt_ratio"] == pytest.approx(0.4, abs=0.1) and "pan_ratio" not in rates[0]
    assert "the input ended" in rates[1]["detail"] or "specified_angle came" in rates[1]["detail"]
    assert rates[0]["command_count"] > 20
    assert not [f for f in found if f["check"] == "repeat"]
