"""Shared test fixtures: a real RTSP camera (gst-rtsp-server) on 127.0.0.1."""

from __future__ import annotations

import os
import signal
import subprocess
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.collected import ALL_ITEMS

# A suite started in the background by a script (`nohup`, `cmd &`) inherits Ctrl-C
# ignored, and so would every tool it starts: the tests that interrupt a tool (Ctrl-C
# stops a check, a recording) would see the tool carry on. The tools get the default.
if hasattr(signal, "SIGINT") and signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

CAMERA_SCRIPT = Path(__file__).resolve().parent / "rtsp_camera.py"
SYSTEM_PYTHON = "/usr/bin/python3"
# With this set (.ci/run does), the video tests fail instead of skipping without the server.
REQUIRE_RTSP = os.environ.get("GIMBAL_REQUIRE_RTSP") == "1"
DOCUMENT_PATH = "/cam/realmonitor?channel=1&subtype={subtype}"


def rtsp_server_available() -> bool:
    if not os.path.exists(SYSTEM_PYTHON):
        return False
    probe = (
        "import gi; gi.require_version('GstRtspServer', '1.0'); "
        "from gi.repository import Gst, GstRtspServer; Gst.init(None); "
        "assert Gst.ElementFactory.find('x264enc') and Gst.ElementFactory.find('rtph264pay')"
    )
    done = subprocess.run([SYSTEM_PYTHON, "-c", probe], capture_output=True, timeout=30)
    return done.returncode == 0


@dataclass
class RtspCamera:
    """A running test camera: ``port`` on 127.0.0.1, ``url(subtype)`` with credentials."""

    process: subprocess.Popen[str]
    port: int

    def url(self, subtype: int = 0, user: str = "admin", password: str = "admin") -> str:
        path = DOCUMENT_PATH.format(subtype=subtype)
        return f"rtsp://{user}:{password}@127.0.0.1:{self.port}{path}"

    def kill(self) -> None:
        """The camera dies at once (power cut): no RTSP TEARDOWN, the TCP link just drops."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGKILL)
            self.process.wait(10)


def start_camera(*options: str) -> RtspCamera:
    process = subprocess.Popen(
        [SYSTEM_PYTHON, str(CAMERA_SCRIPT), *options],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        encoding="utf-8",
    )
    assert process.stdout is not None
    line = process.stdout.readline()
    if not line.startswith("READY "):
        process.kill()
        _, err = process.communicate(10)
        raise RuntimeError(f"the test camera did not start: {line!r} {err[-2000:]}")
    return RtspCamera(process, int(line.split()[1]))


@pytest.fixture(scope="session")
def rtsp_available() -> bool:
    available = rtsp_server_available()
    if not available and REQUIRE_RTSP:
        pytest.fail("gst-rtsp-server (python3-gi, gir1.2-gst-rtsp-server-1.0) is missing")
    return available


@pytest.fixture
def rtsp_camera_factory(rtsp_available: bool) -> Iterator[Callable[..., RtspCamera]]:
    """Starts test cameras (options of tests/rtsp_camera.py); all are stopped afterwards."""
    if not rtsp_available:
        pytest.skip("needs gst-rtsp-server through /usr/bin/python3 (see .ci/run)")
    started: list[RtspCamera] = []

    def start(*options: str) -> RtspCamera:
        camera = start_camera(*options)
        started.append(camera)
        return camera

    yield start
    for camera in started:
        if camera.process.poll() is None:
            camera.process.terminate()
            try:
                camera.process.wait(5)
            except subprocess.TimeoutExpired:
                camera.kill()
        camera.process.communicate()


@pytest.fixture
def rtsp_camera(rtsp_camera_factory: Callable[..., RtspCamera]) -> RtspCamera:
    """One test camera: H.264 640x360 at 30 fps, digest auth admin/admin."""
    return rtsp_camera_factory()


@pytest.hookimpl(tryfirst=True)
@pytest.fixture
def india_time(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """This process in UTC+05:30 (no summer time, so the offset is known): local times
    in tests of --local-time."""
    import time

    monkeypatch.setenv("TZ", "IST-05:30")
    time.tzset()
    yield
    monkeypatch.undo()
    time.tzset()


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Keep every collected test before -m / -k deselect some (tests/test_quick_tier.py
    checks the marks of all of them, in a quick run too)."""
    config.stash[ALL_ITEMS] = list(items)
