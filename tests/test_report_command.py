"""`gimbal-analyzer report`: one self-contained HTML file, checked in a real headless Chromium."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from analyzer.cli import main
from analyzer.samplegen import write_samples
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.ground import Step
from analyzer.sim.offline import run_offline

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
REQUIRE = os.environ.get("GIMBAL_REQUIRE_CHROMIUM") == "1"
PLOTS = ("plot-pitch", "plot-yaw", "plot-rates", "plot-health", "plot-altitude", "plot-track")
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--hide-scrollbars",
    "--virtual-time-budget=5000",
)


@pytest.fixture(scope="module")
def samples(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    return {p.name: p for p in write_samples(tmp_path_factory.mktemp("samples"))}


def report(tmp_path: Path, source: Path, *extra: str) -> Path:
    out = tmp_path / f"{source.stem}.html"
    assert main(["report", str(source), "-o", str(out), *extra]) == 0
    return out


def browser(
    page: Path, tmp_path: Path, *args: str, fragment: str = ""
) -> subprocess.CompletedProcess[str]:
    """Run Debian's Chromium headless on ``page`` (and its ``#fragment``), fresh profile."""
    if CHROMIUM is None:
        if REQUIRE:
            pytest.fail("chromium is not installed (.ci/run installs it)")
        pytest.skip("chromium is not installed")
    profile = tmp_path / f"profile-{len(list(tmp_path.glob('profile-*')))}"
    address = page.as_uri() + fragment
    command = [CHROMIUM, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args, address]
    return subprocess.run(
        command, capture_output=True, text=True, timeout=120, check=False, encoding="utf-8"
    )


def load(page: Path, tmp_path: Path, fragment: str = "") -> tuple[str, list[str]]:
    """The DOM after the page's scripts ran, and every console message it produced."""
    done = browser(
        page, tmp_path, "--enable-logging=stderr", "--v=0", "--dump-dom", fragment=fragment
    )
    assert done.returncode == 0, done.stderr[-2000:]
    console = [line for line in done.stderr.splitlines() if ":CONSOLE" in line]
    return done.stdout, console


def canvases(dom: str) -> dict[str, tuple[int, int]]:
    """plot id -> (painted pixels sampled, data points) as the page recorded them."""
    found = {}
    for tag in re.findall(r"<canvas [^>]*>", dom):
        ident = re.search(r'id="([^"]+)"', tag)
        painted = re.search(r'data-painted="(\d+)"', tag)
        points = re.search(r'data-points="(\d+)"', tag)
        assert ident and painted and points, tag
        found[ident.group(1)] = (int(painted.group(1)), int(points.group(1)))
    return found


def session(path: Path) -> Path:
    """A simulated flight with a gimbal that does not always obey, as a candump log."""
    steps = (
        Step(1.0, "specified_angle", {"yaw_deg": 45}),
        Step(6.5, "gimbal_control", {"tilt_speed_dps": -15}, until=8.5),
        Step(12.0, "tracking", {"x": 4096, "y": 4096, "width": 320, "height": 240}),
        Step(18.0, "look_down"),
        Step(24.0, "forward"),
    )
    config = SimConfig(uav=True, behaviour=Behaviour(reach=0.7, drift_s=1.0))
    frames, _ = run_offline(steps, 30.0, config, start=1_700_000_000.0)
    lines = [f"({f.time:.6f}) can0 {f.can_id:08X}#{f.data.hex().upper()}" for f in frames]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_report_is_self_contained(samples: dict[str, Path], tmp_path: Path) -> None:
    page = report(tmp_path, samples["flight-candump.log"]).read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and "Chart.js v4" in page
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", page)
    assert "<link" not in page and "@import" not in page and "sourceMappingURL" not in page
    for words in (
        "Overview",
        "Gimbal attitude",
        "Commanded and measured rates",
        "Feedback health",
        "UAV",
        "Responses",
        "Diagnostics",
    ):
        assert f"<h2>{words}</h2>" in page
    assert "pitch -45.0 not reached within 5 s" in page  # a response row
    assert "<th>yaw reference</th>" in page
    assert "crc_mismatch" in page and "line 630" in page  # the diagnostics
    assert len(page) < 600_000


@pytest.mark.slow
def test_report_loads_in_chromium_with_every_plot_drawn(tmp_path: Path) -> None:
    page = report(tmp_path, session(tmp_path / "flight.log"))
    # The yaw target's row says which reference judged it and why.
    assert '<td>north<br><span class="small">FF13 present</span></td>' in page.read_text(
        encoding="utf-8"
    )
    dom, console = load(page, tmp_path)
    assert console == []  # no error, no warning, no message at all
    assert 'data-plots-ready="yes"' in dom
    drawn = canvases(dom)
    assert sorted(drawn) == sorted(PLOTS)
    for plot, (painted, points) in drawn.items():
        assert painted > 500 and points > 5, plot
    assert "not obeyed" in dom and "stopped short" in dom and "still moving" in dom
    shot = tmp_path / "report.png"
    done = browser(page, tmp_path, "--window-size=1280,3600", f"--screenshot={shot}")
    assert done.returncode == 0, done.stderr[-2000:]
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 50_000


@pytest.mark.slow
@pytest.mark.parametrize("name", ["idu-tcp.pcap", "uart-dump.bin"])
def test_report_of_every_sample_loads(name: str, samples: dict[str, Path], tmp_path: Path) -> None:
    page = report(tmp_path, samples[name])
    dom, console = load(page, tmp_path)
    assert console == [] and 'data-plots-ready="yes"' in dom
    for plot, (painted, _) in canvases(dom).items():
        assert painted > 0, plot
    if name == "uart-dump.bin":  # no times and no feedback: said instead of empty plots
        assert list(canvases(dom)) == ["plot-track"]  # positions need no clock
        assert "nothing to plot over time" in dom and "no timestamps" in dom
        # the responses say why there are none, not that no command had an effect
        responses = page.read_text(encoding="utf-8").split("<h2>Responses</h2>")[1].split("<h2>")[0]
        assert "carries no timestamps" in responses and "cannot be timed" in responses
        assert "no command with a visible effect" not in responses


@pytest.mark.slow
def test_report_of_a_demo_recording(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    recording = tmp_path / "demo.mcap"
    assert main(["demo", "--no-tui", "--duration", "3", "-o", str(recording)]) == 0
    capsys.readouterr()
    assert main(["analyze", str(recording)]) == 0
    assert "verdicts:" in capsys.readouterr().out
    page = report(tmp_path, recording)
    assert "demo.mcap (mcap)" in page.read_text(encoding="utf-8")
    dom, console = load(page, tmp_path)
    assert console == [] and len(canvases(dom)) == len(PLOTS)


def test_output_is_never_overwritten_silently(
    samples: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "report.html"
    out.write_text("keep me", encoding="utf-8")
    source = str(samples["idu-tcp.pcap"])
    assert main(["report", source, "-o", str(out)]) == 2
    assert out.read_text(encoding="utf-8") == "keep me" and "--force" in capsys.readouterr().err
    assert main(["report", source, "-o", str(out), "--force"]) == 0
    assert out.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert main(["report", source, "-o", source, "--force"]) == 2
    assert "input" in capsys.readouterr().err
    assert samples["idu-tcp.pcap"].read_bytes()[:4] == b"\xd4\xc3\xb2\xa1"


def test_the_report_shows_each_stick_movement_with_its_figures(
    samples: dict[str, Path], tmp_path: Path
) -> None:
    """A ground station driving like a pilot: each movement, the re-sent target and the
    tracking session are one finding each, with the figures that judged them."""
    page = report(tmp_path, samples["pilot-candump.log"])
    responses = page.read_text(encoding="utf-8").split("<h2>Responses</h2>")[1].split("<h2>")[0]
    rate = responses.split('data-check="rate"')[1].split("<h3")[0]
    assert "<th>pan ratio</th><th>tilt ratio</th><th>lag s</th><th>commands</th>" in rate
    rows = re.findall(r"<tr><td>([^<]+)</td><td><span[^>]*>obeyed</span></td>(.*?)</tr>", rate)
    assert len(rows) == 3
    numbers = [re.findall(r'<td class="num">([^<]*)</td>', cells) for _, cells in rows]
    assert ["1.00", "", "0.30", "49", "0.050", "0.05"] in numbers  # pan, 0.3 s late
    target = responses.split('data-check="target"')[1].split("<h3")[0]
    assert "<th>sent</th>" in target and "sent 16 times over 3.0 s" in target
    tracking = responses.split('data-command="tracking_stop"')[1].split("<h3")[0]
    assert "<th>updates/s</th>" in tracking and '<td class="num">10.0</td>' in tracking
    assert '<td class="num">60</td>' in tracking  # the session's box updates
    # the summary table: a row per command and check, the feedback in its health column
    assert re.search(r"<td>feedback</td><td>feedback</td><td class=\"num\">1</td>", responses)
