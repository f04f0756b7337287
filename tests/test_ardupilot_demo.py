"""`export ardupilot` writes the driver and its page; `demo --ardupilot` runs it live against
the simulated gimbal and records what `analyze` judges (a few real seconds)."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest

from analyzer.cli import main
from analyzer.export.ardupilot import DRIVER_NAME, lua_text, markdown_text


def test_export_writes_the_driver_and_its_page_and_replaces_neither_unasked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    driver = tmp_path / DRIVER_NAME
    assert main(["export", "ardupilot", "-o", str(driver)]) == 0
    assert driver.read_text() == lua_text()
    page = driver.with_suffix(".md")
    assert page.read_text() == markdown_text()
    assert "VSH_CAN_DRV" in page.read_text() and "MNT1_TYPE | 9" in page.read_text()
    assert main(["export", "ardupilot", "-o", str(driver)]) == 2
    assert "use --force" in capsys.readouterr().err
    assert main(["export", "ardupilot", "-o", str(driver), "--check"]) == 0
    page.write_text("edited")
    assert main(["export", "ardupilot", "-o", str(driver), "--check"]) == 1
    assert "out of date" in capsys.readouterr().out
    assert main(["export", "ardupilot", "-o", str(driver), "--force"]) == 0
    assert page.read_text() == markdown_text()


@pytest.mark.slow
def test_demo_ardupilot_records_the_drivers_view_and_analyze_finds_the_gimbal_obeyed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analyzer.mcapio.read.reader import Recording, read_events

    driver = tmp_path / DRIVER_NAME
    driver.write_text(lua_text())
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
    metadata = Recording(path).metadata()["gimbal-analyzer"]
    assert metadata["ardupilot_driver"] == DRIVER_NAME
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
    broken.write_text("local = 1\n")
    path = tmp_path / "x.mcap"
    assert main(["demo", "--no-tui", "-o", str(path), "--ardupilot", str(broken)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"gimbal-analyzer demo: error: --ardupilot {broken}: Lua: broken.lua:1: "
        "<name> expected near '='"
    ]
    assert not path.exists()
    failing = tmp_path / "failing.lua"
    failing.write_text("function update()\n  mount:get_rate_target()\nend\nreturn update, 100\n")
    code = main(
        ["demo", "--no-tui", "--duration", "2", "-o", str(path), "--ardupilot", str(failing)]
    )
    assert code == 1
    assert "Lua: failing.lua:2: mount:get_rate_target: got 0 arguments, expected 1" in (
        capsys.readouterr().err
    )
