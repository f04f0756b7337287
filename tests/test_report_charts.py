"""The report's charts say exactly what happened: exact time labels, a mark for every command,
a UAV track inside its axes at equal scale, pictures at the verdict's moment, status texts.

Checked in the page's embedded data and in headless Chromium (what the charts drew)."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from analyzer.mcapio.read.video import Thumbnail
from analyzer.report import camera
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.ground import DEMO_PERIOD, DEMO_SCRIPT, Step
from analyzer.sim.offline import run_offline
from tests.test_report_command import load, report

START = 1_700_000_000.841  # a start with a fraction of a second


def demo_flight(path: Path, duration: float = 31.0) -> Path:
    """What ``demo --duration 31 --fall-short 0.7 --drift 1 --ignore tracking_stop`` plays
    (the demo's script, started over every 15 s), as a candump log."""
    steps: list[Step] = []
    for lap in range(int(duration // DEMO_PERIOD) + 1):
        for step in DEMO_SCRIPT:
            shift = lap * DEMO_PERIOD
            until = step.until + shift if step.until is not None else None
            if step.at + shift < duration:
                steps.append(replace(step, at=step.at + shift, until=until))
    behaviour = Behaviour(reach=0.7, drift_s=1.0, ignore=frozenset({"tracking_stop"}))
    config = SimConfig(uav=True, behaviour=behaviour)
    frames, _ = run_offline(tuple(steps), duration, config, start=START)
    lines = [f"({f.time:.6f}) can0 {f.can_id:08X}#{f.data.hex().upper()}" for f in frames]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def embedded(page: Path) -> dict[str, Any]:
    """The plot data the page carries."""
    found = re.search(r'<script id="report-data" type="application/json">(.*?)</script>',
                      page.read_text(encoding="utf-8"), re.S)  # fmt: skip
    assert found
    data: dict[str, Any] = json.loads(found.group(1).replace("<\\/", "</"))
    return data


def axes(dom: str) -> dict[str, dict[str, Any]]:
    """plot id -> its axes as the page recorded them (range, pixels, ticks, points)."""
    found = {}
    for tag in re.findall(r"<canvas [^>]*>", dom):
        ident = re.search(r'id="([^"]+)"', tag)
        recorded = re.search(r"data-axes=\"([^\"]+)\"", tag)
        assert ident and recorded, tag
        found[ident.group(1)] = json.loads(recorded.group(1).replace("&quot;", '"'))
    return found


@pytest.fixture(scope="module")
def flight(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any], str]:
    """The demo flight's report, its embedded data and its DOM after Chromium drew it."""
    folder = tmp_path_factory.mktemp("charts")
    page = report(folder, demo_flight(folder / "demo31.log"))
    dom, console = load(page, folder)
    assert console == [] and 'data-plots-ready="yes"' in dom
    return page, embedded(page), dom


@pytest.mark.slow
def test_every_point_of_the_uav_track_is_inside_the_axes_at_equal_scale(
    flight: tuple[Path, dict[str, Any], str],
) -> None:
    _, data, dom = flight
    east = [p[0] for p in data["track"]]
    assert max(east) - min(east) > 120  # the orbit runs east 0-150 m
    track = axes(dom)["plot-track"]
    x, y = track["x"], track["y"]
    assert len(track["points"]) == len(data["track"])
    for e, n in track["points"]:
        assert x["min"] <= e <= x["max"] and y["min"] <= n <= y["max"], (e, n)
    metres_per_pixel = ((x["max"] - x["min"]) / x["pixels"], (y["max"] - y["min"]) / y["pixels"])
    assert metres_per_pixel[0] == pytest.approx(metres_per_pixel[1], rel=0.005)


def _label_time(label: str) -> float:
    """Seconds of the day of a tick label such as ``22:13:25Z`` or ``22:13:25.500Z``."""
    found = re.fullmatch(r"(\d\d):(\d\d):(\d\d(?:\.\d{1,3})?)Z", label)
    assert found, label
    hours, minutes, seconds = found.groups()
    return int(hours) * 3600 + int(minutes) * 60 + float(seconds)


@pytest.mark.slow
def test_time_labels_are_exact_times_not_the_start_second(
    flight: tuple[Path, dict[str, Any], str],
) -> None:
    _, data, dom = flight
    assert data["start"] == pytest.approx(START)
    for plot, drawn in axes(dom).items():
        if plot == "plot-track":
            continue
        ticks = drawn["x"]["ticks"]
        assert len(ticks) >= 3, plot
        for value, label in ticks:
            exact = (START + value) % 86400
            assert _label_time(label) == pytest.approx(exact, abs=0.0006), (plot, value, label)
        # round times of day: whole seconds here (31 s on 700-odd pixels)
        assert all(label.count(".") == 0 for _, label in ticks), ticks


@pytest.mark.slow
def test_every_command_gets_its_mark(flight: tuple[Path, dict[str, Any], str]) -> None:
    _, data, _ = flight
    # (seconds into the script, label) of every mark
    marks = [(round(data["start"] + t - START, 1), label) for t, label in data["marks"]]
    at = dict(marks)
    for lap in (0.0, DEMO_PERIOD):
        assert at[lap + 3.6].startswith("specified_angle yaw 90")
        assert at[lap + 4.8].startswith("specified_angle pitch -45")  # same name, 1.2 s later
        assert at[lap + 5.5].startswith("zoom zoom_in")
        assert at[lap + 6.5].startswith("zoom stop")  # same name as the one before
    # The stick goes from tilting (0.5 s) straight to panning (2.2 s) without coming back
    # to its centre: one movement of the stream, one mark.
    played = [
        s.at + lap
        for lap in (0.0, DEMO_PERIOD, 2 * DEMO_PERIOD)
        for s in DEMO_SCRIPT
        if not (s.name == "gimbal_control" and s.at == 2.2)
    ]
    played = [t for t in played if t < 31.0]
    assert sorted(t for t, _ in marks) == pytest.approx(sorted(played), abs=0.06)
    # a stick stream (gimbal_control every 50 ms for 3 s) is one mark, not sixty
    sticks = [(t, label) for t, label in marks if label.startswith("gimbal_control")]
    assert [t for t, _ in sticks] == [0.5, 15.5, 30.5]
    assert sticks[0][1].startswith("gimbal_control pan 0.00 deg/s til")


@pytest.mark.slow
def test_status_texts_of_the_flight_controller_are_listed(
    flight: tuple[Path, dict[str, Any], str],
) -> None:
    page, _, dom = flight
    section = (
        page.read_text(encoding="utf-8").split("<h2>UAV status texts</h2>")[1].split("<h2>")[0]
    )
    texts = re.findall(r"<tr><td>([0-9:.]+Z)</td><td>([^<]+)</td></tr>", section)
    assert texts and ("22:13:20.841Z", "UAV armed") in texts
    assert "UAV armed" in dom


@pytest.mark.slow
def test_zoom_keeps_exact_labels_and_shows_the_samples_in_range(
    flight: tuple[Path, dict[str, Any], str], tmp_path: Path
) -> None:
    page, data, _ = flight
    zoomed = page.with_name("zoomed.html")
    zoomed.write_bytes(page.read_bytes())
    dom, console = load(zoomed, tmp_path, "#zoom=3.2,5.6")
    assert console == [] and 'data-zoom="3.200,5.600"' in dom
    pitch = axes(dom)["plot-pitch"]
    assert (pitch["x"]["min"], pitch["x"]["max"]) == (3.2, 5.6)
    for value, label in pitch["x"]["ticks"]:
        assert _label_time(label) == pytest.approx((START + value) % 86400, abs=0.0006)
    inside = [r for r in data["attitude"] if 3.2 <= r[0] <= 5.6]
    shown = {(p[0], p[1]) for p in pitch["points"] if 3.2 <= p[0] <= 5.6}
    assert len(inside) > 3 and {(r[0], r[1]) for r in inside} <= shown  # every sample


def picture(t: float) -> Thumbnail:
    return Thumbnail("main", t, f"jpeg at {t}".encode())


def test_pictures_show_the_moment_before_the_command_and_the_verdict_s_moment() -> None:
    failed = {
        "command": "specified_angle",
        "check": "target",
        "time": 100.0,
        "verdict": "not_obeyed",
        "detail": "never moved",
        "observed_at": 105.0,
    }
    gap = {"command": "feedback", "check": "feedback_gap", "time": 50.0,
           "verdict": "not_obeyed", "detail": "no feedback for 3 s", "observed_at": 53.0}  # fmt: skip
    shown = camera.shown_findings([failed, gap])
    assert shown == [failed]  # none for the link as a whole
    pictures = [picture(90.0 + 2 * i) for i in range(12)]  # every 2 s, 90-112 s
    choice = camera.choose(iter(pictures), 90.0, 112.0, shown)
    before = choice.get(camera.before_command(failed))
    wanted = camera.at_verdict(failed)
    assert wanted is not None
    after = choice.get(wanted)
    assert before is not None and before.time == 100.0  # at or before the command, never after
    assert after is not None and after.time == 104.0  # the nearest (106 s is as near)
    html = camera.camera_section(choice, shown)
    assert "before the command" in html and "at the verdict" in html
    assert html.count("<img") == 8 + 2  # the strip, then the pair
    assert "decided at" in html and "no feedback for 3 s" not in html
    # a command before the first picture: no 'before' picture, said so
    early = dict(failed, time=80.0, observed_at=91.0)
    choice = camera.choose(iter(pictures), 80.0, 112.0, [early])
    assert choice.get(camera.before_command(early)) is None
    assert "no picture before the command" in camera.camera_section(choice, [early])


def test_only_the_chosen_pictures_are_kept_while_reading() -> None:
    finding = {"command": "look_down", "check": "target", "time": 500.0,
               "verdict": "partial", "detail": "stopped short", "response_s": 3.0}  # fmt: skip
    choice = camera.choose((picture(float(t)) for t in range(0, 10_000)), 0.0, 9999.0, [finding])
    kept = {id(p) for p in choice.best.values()}
    assert len(kept) <= camera.STRIP_SIZE + 2 and choice.count == 10_000
    after = camera.at_verdict(finding)
    assert after is not None and after.time == 503.0  # no feedback moment: command + response


@pytest.mark.slow
def test_with_local_time_the_page_says_which_times_are_local(
    flight: tuple[Path, dict[str, Any], str], tmp_path: Path
) -> None:
    from analyzer.cli import main

    page = tmp_path / "local.html"
    log = flight[0].with_name("demo31.log")
    assert main(["--local-time", "report", str(log), "-o", str(page)]) == 0
    assert "Times in the tables are local time" in page.read_text(encoding="utf-8")
    assert "Times are UTC." in flight[0].read_text(encoding="utf-8")
