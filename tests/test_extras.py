"""A plain install does the everyday work; each extra adds its wing, and says when it is missing.

Each command runs in a fresh interpreter in which the modules of a missing extra cannot
be imported (as in a venv without it): the core commands work as before, and a command
that needs the extra says in one line which one to install. CI also installs the wheel
without any extra into a fresh venv and runs the demo from it (``.ci/run``).
"""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from analyzer.extras import ARDUPILOT, EXTRAS, FLEET, VIDEO
from analyzer.sim.ground import Step
from tests.camera_flights import record

# Each test runs the command line in fresh interpreters (and some a demo): seconds each.
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "flight-candump.log"

# A fresh interpreter where the modules named first cannot be imported, then the CLI.
WITHOUT = """
import importlib.abc, sys
missing = set(sys.argv[1].split(",")) - {""}
class Missing(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in missing:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None
sys.meta_path.insert(0, Missing())
from analyzer.cli import main
code = main(sys.argv[2:])
loaded = sorted({m.split(".")[0] for m in sys.modules} & missing)
assert not loaded, f"imported all the same: {loaded}"
sys.exit(code)
"""


def run_without(
    modules: tuple[str, ...], *args: str, cwd: Path
) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-c", WITHOUT, ",".join(modules), *args],
        cwd=cwd, env=env, capture_output=True, text=True, encoding="utf-8", timeout=180,
    )  # fmt: skip


def everything_but(*kept: str) -> tuple[str, ...]:
    return tuple(m for extra in EXTRAS if extra.name not in kept for m in extra.modules)


@pytest.fixture(scope="module")
def video_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short recording with the simulated camera's video and a zoom to judge."""
    steps = (Step(0.3, "zoom", {"action": "zoom_in_2x"}),)
    return record(tmp_path_factory.mktemp("video") / "zoom.mcap", steps, 3.0)


def test_the_core_commands_run_without_any_extra(tmp_path: Path) -> None:
    missing = everything_but()
    commands = [
        ("decode", str(SAMPLE), "--summary"),
        ("analyze", str(SAMPLE)),
        ("report", str(SAMPLE), "-o", "report.html", "-q"),
        ("convert", str(SAMPLE), "-o", "flight.mcap", "-q"),
        ("info", "flight.mcap"),
        ("send", "specified_angle", "--yaw", "45"),
        ("demo", "--no-tui", "--duration", "2", "-o", "demo.mcap"),
        ("export", "dbc", "-o", "gimbal.dbc"),
        ("export", "ardupilot", "-o", "driver.lua"),
        ("layout", "-o", "layout.json"),
        ("commands",),
        ("check", "--help"),
        ("record", "--help"),
        ("monitor", "--help"),
    ]
    for command in commands:
        done = run_without(missing, *command, cwd=tmp_path)
        assert done.returncode == 0, (command, done.stderr)
        assert "extra" not in done.stderr, (command, done.stderr)
    assert (tmp_path / "demo.mcap").stat().st_size > 0 and (tmp_path / "report.html").exists()


@pytest.mark.parametrize(
    ("extra", "command"),
    [
        (VIDEO, ("demo", "--no-tui", "--duration", "2", "--video", "main")),
        (VIDEO, ("record", "--source", "tcp:127.0.0.1:9", "--video", "main", "-o", "x.mcap")),
        (FLEET, ("table", str(SAMPLE), "-o", "fleet")),
        (FLEET, ("fleet", "fleet")),
        (ARDUPILOT, ("demo", "--no-tui", "--duration", "2", "--ardupilot", "driver.lua")),
    ],
)
def test_a_command_that_needs_a_missing_extra_says_which_in_one_line(
    extra: object, command: tuple[str, ...], tmp_path: Path
) -> None:
    (tmp_path / "driver.lua").write_text("-- a driver\n", encoding="utf-8")
    done = run_without(everything_but(), *command, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    (line,) = done.stderr.splitlines()
    assert f"needs the {extra.name} extra" in line  # type: ignore[attr-defined]
    assert f"install gimbal-analyzer[{extra.name}]" in line  # type: ignore[attr-defined]
    assert not list(tmp_path.glob("*.mcap")) and not (tmp_path / "fleet").exists()


def test_analyze_of_a_video_recording_without_video_says_the_camera_was_not_judged(
    video_recording: Path, tmp_path: Path
) -> None:
    with_video = run_without((), "analyze", "--json", str(video_recording), cwd=tmp_path)
    without = run_without(VIDEO.modules, "analyze", "--json", str(video_recording), cwd=tmp_path)
    assert with_video.returncode == without.returncode == 0, without.stderr
    judged = [line for line in with_video.stdout.splitlines() if line not in without.stdout]
    assert judged, "the camera judgement adds findings"
    assert all(line in with_video.stdout for line in without.stdout.splitlines())
    (note,) = [line for line in without.stderr.splitlines() if line.startswith("note:")]
    assert "camera commands not judged" in note and "gimbal-analyzer[video]" in note
    assert "note:" not in with_video.stderr


def test_report_and_info_of_a_video_recording_without_video(
    video_recording: Path, tmp_path: Path
) -> None:
    report = run_without(
        VIDEO.modules, "report", str(video_recording), "-o", "r.html", cwd=tmp_path
    )
    assert report.returncode == 0, report.stderr
    notes = [line for line in report.stderr.splitlines() if "extra" in line]
    assert len(notes) == 1 and "camera commands not judged" in notes[0]
    assert "camera commands not judged" in (tmp_path / "r.html").read_text(encoding="utf-8")
    info = run_without(VIDEO.modules, "info", str(video_recording), cwd=tmp_path)
    assert info.returncode == 0, info.stderr
    assert "/camera/main  h264 size not read" in info.stdout
    assert "the video extra is not installed" in info.stdout


def test_record_and_check_against_a_simulated_gimbal_without_any_extra(tmp_path: Path) -> None:
    port = free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    missing = ",".join(everything_but())
    gimbal = subprocess.Popen(
        [sys.executable, "-c", WITHOUT, missing, "simulate", "--on", f"tcp:127.0.0.1:{port}"],
        cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    try:
        wait_for_port(port)
        record = run_without(
            everything_but(), "record", "--source", f"tcp:127.0.0.1:{port}", "-o", "rec.mcap",
            "--duration", "2", "-q", cwd=tmp_path,
        )  # fmt: skip
        assert record.returncode == 0, record.stderr
        check = run_without(
            everything_but(), "check", "--to", f"tcp:127.0.0.1:{port}", "--report", "bench.html",
            cwd=tmp_path,
        )  # fmt: skip
        assert check.returncode == 0, check.stdout + check.stderr
    finally:
        gimbal.kill()
        gimbal.wait(10)
    assert (tmp_path / "bench.html").exists() and (tmp_path / "rec.mcap").stat().st_size > 0


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def wait_for_port(port: int, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.5):
            return
        time.sleep(0.1)
    raise AssertionError(f"the simulated gimbal never listened on {port}")


def test_each_extra_alone_missing_leaves_the_others_working(tmp_path: Path) -> None:
    """The fleet without video and lupa; the demo's video without the fleet."""
    table = run_without(everything_but("fleet"), "table", str(SAMPLE), "-o", "fleet", cwd=tmp_path)
    assert table.returncode == 0, table.stderr
    fleet = run_without(everything_but("fleet"), "fleet", "fleet", cwd=tmp_path)
    assert fleet.returncode == 0 and "flights" in fleet.stdout.lower(), fleet.stderr
    demo = run_without(
        FLEET.modules + ARDUPILOT.modules,
        "demo", "--no-tui", "--duration", "5", "--video", "main", "-o", "video.mcap",
        cwd=tmp_path,
    )  # fmt: skip
    assert demo.returncode == 0, demo.stderr


def test_the_python_api_without_the_fleet_extra(video_recording: Path, tmp_path: Path) -> None:
    code = (
        "import analyzer, sys\n"
        f"print(len(list(analyzer.analyze({str(SAMPLE)!r}))))\n"
        "try:\n"
        f"    analyzer.Recording({str(video_recording)!r}).table('/gimbal/command')\n"
        "except analyzer.extras.MissingExtra as exc:\n"
        "    print(exc)\n"
    ).replace("analyzer.extras.MissingExtra", "__import__('analyzer.extras').extras.MissingExtra")
    script = WITHOUT.split("from analyzer.cli")[0] + code
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-c", script, ",".join(FLEET.modules)],
        cwd=tmp_path, env=env, capture_output=True, text=True, encoding="utf-8", timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    count, message = done.stdout.splitlines()
    assert int(count) > 0 and "Recording.table needs the fleet extra" in message
