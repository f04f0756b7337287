"""Camera commands judged from the video: the simulated camera's zoom, palette and PiP, as
`analyze` finds them in recordings of simulated flights (the aircraft climbing and orbiting)."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import pytest

from analyzer.mcapio.read.reader import read_events
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE
from analyzer.sim.ground import Step
from tests.camera_flights import Lens, camera_findings, record
from tests.fleet_flights import cli_output

# The simulated camera's video, judged from the picture: recordings of seconds each.
pytestmark = pytest.mark.slow

LOOK_DOWN = Step(0.3, "specified_angle", {"pitch_deg": -45})
ZOOMS = (
    LOOK_DOWN,
    Step(1.5, "zoom", {"action": "zoom_in"}),
    Step(2.3, "zoom", {"action": "stop"}),
    Step(4.0, "zoom", {"action": "zoom_in_2x"}),
    Step(7.0, "specified_angle", {"zoom": 3}),
    Step(10.0, "zoom", {"action": "zoom_out_2x"}),
    Step(12.5, "zoom_1x"),
    Step(14.5, "specified_angle", {"zoom": 20}),
    Step(19.5, "zoom_1x"),
)
ZOOMS_S = 24.0


@pytest.fixture(scope="module")
def zooms(tmp_path_factory: pytest.TempPathFactory) -> list[dict[str, Any]]:
    path = record(tmp_path_factory.mktemp("zooms") / "zooms.mcap", ZOOMS, ZOOMS_S)
    return camera_findings(path)


def by_command(findings: list[dict[str, Any]]) -> list[tuple[str, str]]:
    return [(f["command"], f["verdict"]) for f in findings]


def test_every_zoom_command_is_judged_from_the_picture(zooms: list[dict[str, Any]]) -> None:
    assert by_command(zooms) == [
        ("zoom", "obeyed"),
        ("zoom", "obeyed"),
        ("specified_angle", "obeyed"),
        ("zoom", "obeyed"),
        ("zoom_1x", "obeyed"),
        ("specified_angle", "obeyed"),
        ("zoom_1x", "obeyed"),
    ]
    for finding in zooms:
        assert finding["stream"] == "main"
        assert finding["frame_before"] < finding["time"] < finding["frame_after"]
        assert finding["observed_at"] == finding["frame_after"]


def test_the_measured_scale_is_within_5_percent_of_the_lens(zooms: list[dict[str, Any]]) -> None:
    """The aircraft climbs 6 m/s and orbits at 12 m/s meanwhile: the picture alone changes
    by up to 2x; with that taken out, each step is the lens's own ratio."""
    lens = Lens(ZOOMS, ZOOMS_S)
    for finding in zooms:
        truth = lens.at(finding["frame_after"]) / lens.at(finding["frame_before"])
        assert finding["scale"] == pytest.approx(truth, rel=0.05), finding
    moved = [f for f in zooms if "raw_scale" in f]
    assert moved, "the aircraft's motion changed the picture's scale"
    assert any(abs(math.log(f["raw_scale"] / f["scale"])) > math.log(1.2) for f in moved)


def test_absolute_zooms_are_checked_once_the_zoom_is_known(zooms: list[dict[str, Any]]) -> None:
    """zoom_1x pins the zoom: the specified_angle after it is judged against 1x."""
    pinned = zooms[5]
    assert pinned["command"] == "specified_angle"
    assert pinned["expected_scale"] == pytest.approx(20.0, rel=0.1)
    assert "from 1.0x to 20x" in pinned["detail"]


def test_zoom_while_the_gimbal_pans(tmp_path: Path) -> None:
    steps = (
        Step(0.3, "specified_angle", {"pitch_deg": -30}),
        Step(1.5, "gimbal_control", {"pan_speed_dps": 12}, until=5.0),
        Step(2.0, "zoom", {"action": "zoom_in"}),
        Step(2.6, "zoom", {"action": "stop"}),
        Step(3.5, "zoom", {"action": "zoom_in_2x"}),
    )
    found = camera_findings(record(tmp_path / "pan.mcap", steps, 9.0))
    assert by_command(found) == [("zoom", "obeyed"), ("zoom", "obeyed")]
    lens = Lens(steps, 9.0)
    for finding in found:
        truth = lens.at(finding["frame_after"]) / lens.at(finding["frame_before"])
        assert finding["scale"] == pytest.approx(truth, rel=0.05)


def test_a_camera_that_ignores_zoom(tmp_path: Path) -> None:
    steps = (
        *ZOOMS[:3],
        Step(4.0, "zoom", {"action": "zoom_in_2x"}),
        Step(6.5, "zoom_1x"),
        Step(9.0, "specified_angle", {"zoom": 3}),  # a command it does obey: the zoom is known
        Step(11.5, "zoom_1x"),
    )
    path = record(tmp_path / "ignores.mcap", steps, 14.0, ignore=frozenset({"zoom", "zoom_1x"}))
    found = camera_findings(path)
    assert by_command(found) == [
        ("zoom", "not_obeyed"),
        ("zoom", "not_obeyed"),
        ("zoom_1x", "unknown"),
        ("specified_angle", "obeyed"),
        ("zoom_1x", "not_obeyed"),
    ]
    for finding in found[:3] + found[4:]:
        assert finding["scale"] == pytest.approx(1.0, abs=0.03)
        assert "kept its scale" in finding["detail"]
    # the zoom before is not known: at 1x already, or ignored
    assert "already, or ignored" in found[2]["detail"]
    assert found[3]["scale"] == pytest.approx(3.0, rel=0.05)


def test_a_video_gap_at_the_command_is_unknown(tmp_path: Path) -> None:
    steps = (
        LOOK_DOWN,
        Step(2.0, "zoom", {"action": "zoom_in_2x"}),
        Step(5.0, "zoom", {"action": "zoom_out_2x"}),
    )
    path = record(tmp_path / "gap.mcap", steps, 8.0, gaps=((1.2, 2.6),))
    first, second = camera_findings(path)
    assert (first["command"], first["verdict"]) == ("zoom", "unknown")
    assert first["detail"].startswith("no video at that moment: the last frame of /camera/main")
    assert "scale" not in first
    assert (second["verdict"], second["expected_scale"]) == ("obeyed", 0.5)


def test_the_video_ending_before_the_zoom_settled_is_unknown(tmp_path: Path) -> None:
    steps = (LOOK_DOWN, Step(2.0, "specified_angle", {"zoom": 30}))
    (finding,) = camera_findings(record(tmp_path / "end.mcap", steps, 4.0))
    assert finding["verdict"] == "unknown"
    assert "the video of /camera/main stops" in finding["detail"]


DUAL = (
    LOOK_DOWN,
    Step(3.0, "palette", {"palette": "iron_red"}),
    Step(4.5, "palette", {"palette": "iron_red"}),
    Step(6.0, "palette", {"palette": "rainbow"}),
    Step(7.5, "pip_cycle"),
    Step(9.0, "pip_cycle"),
    Step(10.5, "pip_cycle"),
    Step(12.0, "pip_cycle"),
    Step(13.5, "digital_zoom", {"action": "zoom_in"}),
    Step(14.0, "digital_zoom", {"action": "stop"}),
)


@pytest.mark.parametrize("ignored", [False, True])
def test_palettes_and_pip_on_the_dual_sensor_streams(tmp_path: Path, ignored: bool) -> None:
    ignore = frozenset({"palette", "pip_cycle", "digital_zoom"}) if ignored else frozenset()
    path = record(
        tmp_path / "dual.mcap",
        DUAL,
        15.5,
        ignore=ignore,
        streams=("main", "thermal"),
        gimbal_type=7,
    )
    found = camera_findings(path)
    streams = [f["stream"] for f in found]
    assert streams == ["thermal"] * 3 + ["main"] * 5
    if not ignored:
        assert [f["verdict"] for f in found] == ["obeyed"] * 8
        assert [f.get("palette_changed") for f in found[:3]] == [True, False, True]
        assert "iron_red was on already" in found[1]["detail"]
        assert all(f["layout_changed"] for f in found[3:7])  # round all four layouts
        assert found[7]["scale"] == pytest.approx(3.0, rel=0.05)  # 0.5 s at 4x/s
    else:
        assert [f["verdict"] for f in found] == ["not_obeyed"] * 8
        assert [f.get("palette_changed") for f in found[:3]] == [False] * 3
        assert not any(f["layout_changed"] for f in found[3:7])


def test_convert_writes_the_camera_findings(tmp_path: Path) -> None:
    steps = (LOOK_DOWN, Step(1.5, "zoom", {"action": "zoom_in_2x"}))
    path = record(tmp_path / "in.mcap", steps, 4.5)
    out = tmp_path / "out.mcap"
    cli_output("convert", str(path), "-o", str(out), "-q")
    findings = [
        e.fields
        for e in read_events(out)
        if e.topic == TOPIC_ANALYSIS_RESPONSE and e.fields["check"] == "picture"
    ]
    assert [(f["command"], f["verdict"]) for f in findings] == [("zoom", "obeyed")]
    assert findings[0]["scale"] == pytest.approx(2.0, rel=0.05)


def test_no_camera_findings_without_video(tmp_path: Path) -> None:
    steps = (LOOK_DOWN, Step(1.5, "zoom", {"action": "zoom_in_2x"}))
    path = record(tmp_path / "plain.mcap", steps, 3.0, streams=())
    assert camera_findings(path) == []


def test_the_report_shows_each_camera_finding_with_its_two_frames(tmp_path: Path) -> None:
    from tests.test_report_command import browser

    steps = (
        LOOK_DOWN,
        Step(1.5, "zoom", {"action": "zoom_in_2x"}),
        Step(4.0, "palette", {"palette": "lava"}),
    )
    path = record(tmp_path / "seen.mcap", steps, 7.0, streams=("main", "thermal"))
    page = tmp_path / "seen.html"
    cli_output("report", str(path), "-o", str(page), "-q")
    text = page.read_text(encoding="utf-8")
    section = text.split('<h2 id="camera-judged">')[1].split("<h2>")[0]
    rows = section.split('<div class="judged">')[1]
    assert rows.count("<img") == 4  # before and after, for each of the two commands
    assert "zoom</b> on /camera/main" in rows and "palette</b> on /camera/thermal" in rows
    assert "before: " in rows and "after: " in rows
    done = browser(page, tmp_path, "--dump-dom")
    assert done.returncode == 0, done.stderr[-2000:]
    judged = done.stdout.split('id="camera-judged"')[1].split("<h2>")[0]
    shown = [tuple(map(int, s.split("x"))) for s in re.findall(r'data-shown="(\d+x\d+)"', judged)]
    assert len(shown) == 4
    assert all(width == 240 and height > 100 for width, height in shown)


@pytest.mark.parametrize("ignore", [[], ["--ignore", "zoom"]])
def test_the_demo_records_the_simulated_camera_and_its_zoom_is_judged(
    tmp_path: Path, ignore: list[str]
) -> None:
    """`demo --video main` with no --camera films the simulated gimbal in real time; the
    demo script's zoom in (5.5 s) and stop (6.5 s) are judged from that video."""
    path = tmp_path / "demo.mcap"
    args = ["demo", "--no-tui", "--clean", "--duration", "8.5", "--video", "main", *ignore]
    cli_output(*args, "-o", str(path))
    info = cli_output("info", str(path))
    found = re.search(r"/camera/main\s+h264 640x360\s+([\d.]+) fps", info)
    assert found and float(found.group(1)) >= 10.0, info
    assert "the simulated camera's main stream" in cli_output("info", "--json", str(path))
    zooms = [f for f in camera_findings(path) if f["command"] == "zoom"]
    assert zooms, "the demo's zoom in was judged"
    verdict = "not_obeyed" if ignore else "obeyed"
    assert zooms[0]["verdict"] == verdict, zooms[0]
    if not ignore:  # a second at 6x per second
        assert zooms[0]["scale"] == pytest.approx(7.0, rel=0.15)
