"""`simulate --camera-port`: the simulated camera served over RTSP by GStreamer's RTSP server."""

from __future__ import annotations

import contextlib
import os
import struct
import subprocess
import threading
from pathlib import Path

from analyzer.sim.camera.eye import GimbalEye
from analyzer.sim.camera.frames import MAIN, SUB, THERMAL
from analyzer.sim.camera.stream import Filming

# The system Python that has GObject introspection (Debian's python3-gi).
SYSTEM_PYTHON = os.environ.get("GIMBAL_GI_PYTHON", "/usr/bin/python3")
SERVER = Path(__file__).with_name("rtsp_serve.py")
STREAMS = {0: MAIN, 1: SUB, 2: THERMAL}  # the document's subtypes
START_TIMEOUT_S = 15.0
HEADER = struct.Struct(">BI")  # subtype, length: as rtsp_serve.py reads each picture
PACKAGES = (
    "python3-gi gir1.2-gst-rtsp-server-1.0 gstreamer1.0-rtsp gstreamer1.0-plugins-good "
    "gstreamer1.0-plugins-bad"
)


class CameraServerError(Exception):
    """The RTSP server could not be started (the reason in words)."""


class RtspCamera:
    """GStreamer's RTSP server in a child process (``rtsp_serve.py`` run by the system
    Python), fed by one filming thread per stream of the document: main, sub1, thermal."""

    def __init__(self, eye: GimbalEye, port: int, host: str = "127.0.0.1") -> None:
        self.eye = eye
        self.stopping = threading.Event()
        self.errors: list[str] = []
        self._lock = threading.Lock()
        command = [SYSTEM_PYTHON, str(SERVER), "--host", host, "--port", str(port)]
        try:
            self.process = subprocess.Popen(
                command,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=False,
            )
        except OSError as exc:
            raise CameraServerError(f"cannot run {SYSTEM_PYTHON}: {exc.strerror}") from None
        self.port = self._ready()
        self._threads = [
            threading.Thread(target=self._film, args=(subtype,), daemon=True, name=f"rtsp-{kind}")
            for subtype, kind in STREAMS.items()
        ]

    def _ready(self) -> int:
        """The port from the server's READY line (CameraServerError when it fails)."""
        assert self.process.stdout is not None
        line = b""
        timer = threading.Timer(START_TIMEOUT_S, self.process.kill)
        timer.start()
        try:
            line = self.process.stdout.readline()
        finally:
            timer.cancel()
        words = line.decode(errors="replace").split()
        if len(words) == 2 and words[0] == "READY" and words[1].isdigit():
            return int(words[1])
        self.process.kill()
        error = (self.process.stderr.read() if self.process.stderr else b"").decode(
            errors="replace"
        )
        last = error.strip().splitlines()[-1] if error.strip() else "no answer"
        raise CameraServerError(
            f"GStreamer's RTSP server did not start ({last}); it needs {SYSTEM_PYTHON} with "
            f"Debian's {PACKAGES}"
        )

    def start(self) -> None:
        for thread in self._threads:
            thread.start()

    def _film(self, subtype: int) -> None:
        filming = Filming(self.eye, STREAMS[subtype])

        def deliver(wall: float, unit: bytes, key: bool) -> None:
            pipe = self.process.stdin
            if pipe is None:
                return
            with self._lock:
                pipe.write(HEADER.pack(subtype, len(unit)) + unit)
                pipe.flush()

        try:
            filming.run(self.stopping, deliver)
        except (OSError, ValueError) as exc:  # the server went away
            if not self.stopping.is_set():
                self.errors.append(f"the RTSP server stopped taking pictures: {exc}")
                self.stopping.set()

    def stop(self) -> None:
        self.stopping.set()
        for thread in self._threads:
            if thread.is_alive():
                thread.join(2.0)
        if self.process.stdin is not None:
            with contextlib.suppress(OSError):
                self.process.stdin.close()  # the server ends with its input
        try:
            self.process.wait(5.0)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(5.0)
