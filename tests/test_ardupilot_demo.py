"""`export ardupilot` writes the driver and its page; `demo --ardupilot` runs it live against
the simulated gimbal and records what `analyze` judges (a few real seconds): the UAV status
on its schedule, each attitude reported as its feedback message completes; `--lua
ardupilot` runs it in Lua built as ArduPilot builds it."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path
from types import ModuleType

import pytest

from analyzer.ardupilot import lua_build
from analyzer.cli import main
from analyzer.export.ardupilot import DRIVER_NAME, lua_text, markdown_text
from analyzer.protocol.types import Event
from tests.ardupilot_lua import ardupilot_lua, build_cache, with_locals

__all__ = ["ardupilot_lua"]  # the fixture


def test_export_writes_the_driver_and_its_page_and_replaces_neither_unasked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    driver = tmp_path / DRIVER_NAME
    assert main(["export", "ardupilot", "-o", str(driver)]) == 0
    assert driver.read_text(encoding="utf-8") == lua_text()
    page = driver.with_suffix(".md")
    assert page.read_text(encoding="utf-8") == markdown_text()
    assert "VSH_CAN_DRV" in page.read_text(encoding="utf-8") and "MNT1_TYPE | 9" in page.read_text(
        encoding="utf-8"
    )
    assert main(["export", "ardupilot", "-o", str(driver)]) == 2
    assert "use --force" in capsys.readouterr().err
    assert main(["export", "ardupilot", "-o", str(driver), "--check"]) == 0
    page.write_text("edited", encoding="utf-8")
    assert main(["export", "ardupilot", "-o", str(driver), "--check"]) == 1
    assert "out of date" in capsys.readouterr().out
    assert main(["export", "ardupilot", "-o", str(driver), "--force"]) == 0
    assert page.read_text(encoding="utf-8") == markdown_text()


@pytest.mark.slow
def test_demo_ardupilot_records_the_drivers_view_and_analyze_finds_the_gimbal_obeyed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analyzer.mcapio.read.reader import McapRecording, read_events

    driver = tmp_path / DRIVER_NAME
    driver.write_text(lua_text(), encoding="utf-8")
    path = tmp_path / "ardupilot.mcap"
    args = ["demo", "--no-tui", "--clean", "--duration", "7", "-o", str(path)]
    assert main([*args, "--ardupilot", str(driver)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"demo: simulated gimbal and ArduPilot running {DRIVER_NAME}")
    assert "ardupilot: VSH: mount driver started" in out
    events = list(read_events(path))
    topics = Counter(e.topic for e in events)
    for topic in ("/ardupilot/mount", "/ardupilot/targets", "/gimbal/command", "/uav/attitude"):
        assert topics[topic] > 0, topics
    assert topics["/uav/text"] == 0  # the simulator does not play the UAV: the driver does
    targets = {e.fields["target"] for e in events if e.topic == "/ardupilot/targets"}
    assert {"rate", "angle"} <= targets
    metadata = McapRecording(path).metadata()["gimbal-analyzer"]
    assert metadata["ardupilot_driver"] == DRIVER_NAME
    _status_on_schedule_and_attitudes_as_they_complete(events)
    _valid_against_their_schemas(path, {"/ardupilot/mount", "/ardupilot/targets"})

    assert main(["analyze", str(path), "--json"]) == 0
    found = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    angles = [f for f in found if f["command"] == "specified_angle" and f["check"] == "target"]
    # A target the plan sends in the demo's last moments meets the end of the input
    # (unknown, "before the input ended"); every one the gimbal had time for is obeyed.
    decided = [f for f in angles if "the input ended" not in f["detail"]]
    assert len(decided) >= 2
    assert {f["verdict"] for f in decided} == {"obeyed"}, [f["detail"] for f in angles]
    assert not [f for f in found if f["verdict"] == "not_obeyed"]


def _status_on_schedule_and_attitudes_as_they_complete(events: list[Event]) -> None:
    """The UAV status at 5 Hz or more (attitude 10 Hz) over the run, on a fixed schedule;
    every attitude reported is that of the feedback message completed just before it."""
    for topic, rate in (("/uav/gps", 5), ("/uav/altitude", 5), ("/uav/attitude", 10)):
        times = sorted(e.time for e in events if e.topic == topic)
        assert len(times) / (times[-1] - times[0]) >= rate, (topic, len(times))
    last = None
    reports = 0
    for event in sorted(events, key=lambda e: e.time):
        if event.topic == "/gimbal/attitude":
            last = event.fields
        elif event.topic == "/ardupilot/mount":
            assert last is not None
            reported = event.fields
            assert reported["pitch_deg"] == pytest.approx(last["pitch_deg"], abs=0.01)
            yaw = (reported["yaw_deg"] - last["motor_yaw_deg"] + 180) % 360 - 180
            assert yaw == pytest.approx(0, abs=0.01), (reported, last)
            reports += 1
    assert reports >= 8


@pytest.mark.slow
def test_demo_runs_the_driver_in_lua_built_as_arduPilot_builds_it(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    ardupilot_lua: ModuleType,
    pytestconfig: pytest.Config,
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    cache = build_cache(pytestconfig, tmp_path_factory)  # built there by the fixture
    monkeypatch.setattr(lua_build, "default_cache", lambda: cache)
    driver = tmp_path / DRIVER_NAME
    driver.write_text(lua_text(), encoding="utf-8")
    path = tmp_path / "ardupilot.mcap"
    args = ["demo", "--no-tui", "--clean", "--duration", "4", "-o", str(path)]
    assert main([*args, "--ardupilot", str(driver), "--lua", "ardupilot"]) == 0
    assert "ardupilot: VSH: mount driver started" in capsys.readouterr().out
    from analyzer.mcapio.read.reader import read_events

    topics = Counter(e.topic for e in read_events(path))
    assert topics["/ardupilot/mount"] > 0 and topics["/uav/gps"] >= 15
    # 60 more locals at the top level: past ArduPilot's 100 (lupa's Lua would take 200)
    crowded = tmp_path / "crowded.lua"
    crowded.write_text(with_locals(60), encoding="utf-8")
    refused = [*args, "--force", "--ardupilot", str(crowded), "--lua", "ardupilot"]
    assert main(refused) == 2
    err = capsys.readouterr().err
    assert "too many local variables (limit is 100) in main function" in err
    assert main(["demo", "--no-tui", "-o", str(path), "--lua", "ardupilot"]) == 2
    assert "--lua chooses the Lua of an --ardupilot driver" in capsys.readouterr().err


def _valid_against_their_schemas(path: Path, topics: set[str]) -> None:
    import jsonschema
    from mcap.reader import make_reader

    from analyzer.protocol.schema import topic_schemas

    schemas = topic_schemas()
    seen: Counter[str] = Counter()
    with path.open("rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(topics=list(topics)):
            assert schema is not None and json.loads(schema.data) == schemas[channel.topic]
            jsonschema.validate(json.loads(message.data), schemas[channel.topic])
            seen[channel.topic] += 1
    assert set(seen) == topics


@pytest.mark.slow
def test_demo_ardupilot_refuses_a_driver_that_does_not_compile_and_stops_on_a_script_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    broken = tmp_path / "broken.lua"
    broken.write_text("local = 1\n", encoding="utf-8")
    path = tmp_path / "x.mcap"
    assert main(["demo", "--no-tui", "-o", str(path), "--ardupilot", str(broken)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"gimbal-analyzer demo: error: --ardupilot {broken}: Lua: broken.lua:1: "
        "<name> expected near '='"
    ]
    assert not path.exists()
    failing = tmp_path / "failing.lua"
    failing.write_text(
        "function update()\n  mount:get_rate_target()\nend\nreturn update, 100\n", encoding="utf-8"
    )
    code = main(
        ["demo", "--no-tui", "--duration", "2", "-o", str(path), "--ardupilot", str(failing)]
    )
    assert code == 1
    assert "Lua: failing.lua:2: mount:get_rate_target: got 0 arguments, expected 1" in (
        capsys.readouterr().err
    )
