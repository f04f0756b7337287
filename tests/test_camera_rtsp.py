"""The real RTSP path: `check --video` judges its zoom step from a camera's picture, the
simulated camera served by `simulate --camera-port` (GStreamer's RTSP server) and the
tests' GStreamer camera, which cannot zoom."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from tests.camera_flights import camera_findings
from tests.conftest import RtspCamera
from tests.test_video_record import _env, free_port, gimbal

pytestmark = pytest.mark.slow  # a real RTSP camera


@contextmanager
def simulated_camera(gimbal_port: int) -> Iterator[int]:
    """`simulate` on a loopback TCP port serving its camera over RTSP; yields the camera's
    port (the simulator says it on its own line)."""
    args = ["simulate", "--on", f"tcp:127.0.0.1:{gimbal_port}", "--camera-port", "0"]
    process = subprocess.Popen(
        [sys.executable, "-m", "analyzer", *args, "--quiet", "--duration", "60"],
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        encoding="utf-8",
    )
    try:
        assert process.stdout is not None
        port = None
        for line in process.stdout:
            found = re.search(
                r"camera: rtsp://admin:admin@127\.0\.0\.1:(\d+)/cam/realmonitor", line
            )
            if found:
                port = int(found.group(1))
                break
            if "stops after" in line:
                break
        assert port is not None, process.stderr.read() if process.stderr else ""
        yield port
    finally:
        process.terminate()
        process.wait(15)


def check(gimbal_port: int, camera_port: int, out: Path) -> dict[str, Any]:
    """`check --steps zoom --video main` against them; the zoom step's JSON."""
    done = subprocess.run(
        [
            sys.executable, "-m", "analyzer", "check", "--to", f"tcp:127.0.0.1:{gimbal_port}",
            "--steps", "zoom", "--video", "main", "--camera", f"127.0.0.1:{camera_port}",
            "--json", "-o", str(out),
        ],
        env=_env(), capture_output=True, text=True, timeout=90, encoding="utf-8",
    )  # fmt: skip
    steps = [json.loads(line) for line in done.stdout.splitlines()]
    assert [s["step"] for s in steps] == ["zoom"], done.stderr
    return dict(steps[0])


def test_check_judges_the_zoom_of_the_simulated_camera_over_rtsp(
    rtsp_available: bool, tmp_path: Path
) -> None:
    if not rtsp_available:
        pytest.skip("needs gst-rtsp-server through /usr/bin/python3 (see .ci/run)")
    port = free_port()
    out = tmp_path / "check.mcap"
    with simulated_camera(port) as camera_port:
        step = check(port, camera_port, out)
    assert step["verdict"] == "pass", step
    # zoom in for a second at the simulated lens's 6x per second, then back to 1x
    assert step["scale"] == pytest.approx(7.0, rel=0.15)
    assert step["scale_back"] == pytest.approx(1 / step["scale"], rel=0.05)
    # the recording holds what the check saw: `analyze` judges it the same
    found = camera_findings(out)
    assert [(f["command"], f["verdict"]) for f in found] == [("zoom", "obeyed")] * 2
    assert found[0]["scale"] == pytest.approx(step["scale"], rel=0.02)


def test_a_camera_that_cannot_zoom_fails_the_zoom_step(
    rtsp_camera_factory: Any, tmp_path: Path
) -> None:
    camera: RtspCamera = rtsp_camera_factory("--pattern", "smpte")
    with gimbal() as port:
        step = check(port, camera.port, tmp_path / "check.mcap")
    assert step["verdict"] == "fail"
    assert step["scale"] == pytest.approx(1.0, abs=0.03)
    assert "kept its scale" in step["detail"]
