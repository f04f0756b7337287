"""--foxglove with --video: the camera, its thumbnails and the overlays are served live.

A real RTSP camera (tests/rtsp_camera.py on 127.0.0.1) is recorded next to the simulated
gimbal by ``demo``; a Foxglove WebSocket client connected from the start sees the camera
channels advertised before the first frame and gets every frame the file holds, byte for
byte, with the transforms, the scene and the overlays.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from tests.foxglove_client import FoxgloveClient
from tests.test_live_foxglove import recorded

pytestmark = pytest.mark.slow  # a real RTSP camera

ROOT = Path(__file__).resolve().parent.parent
CAMERA_CHANNELS = {
    "/camera/main": "foxglove.CompressedVideo",
    "/camera/main/thumbnail": "foxglove.CompressedImage",
    "/camera/main/annotations": "foxglove.ImageAnnotations",
    "/camera/main/thumbnail/annotations": "foxglove.ImageAnnotations",
    "/tf": "foxglove.FrameTransforms",
    "/gimbal/scene": "foxglove.SceneUpdate",
}


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT)}


def _url(proc: subprocess.Popen[str]) -> str:
    """The address the command says it serves on (its first 'foxglove:' line)."""
    assert proc.stderr is not None
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if line.startswith("foxglove: "):
            return line.split(" on ")[-1].strip()
        assert line, "the command ended before it said where it serves"
    raise AssertionError("no 'foxglove:' line")


def test_the_live_server_carries_the_camera_as_it_is_recorded(
    rtsp_camera: Any, tmp_path: Path
) -> None:
    out = tmp_path / "demo.mcap"
    said = (tmp_path / "said.txt").open("w", encoding="utf-8")
    proc = subprocess.Popen(
        [
            *(sys.executable, "-m", "analyzer", "demo", "--no-tui", "--duration", "8"),
            *("-o", str(out), "--foxglove", "127.0.0.1:0", "--thumbnail-interval", "0.5"),
            *("--video", "main", "--camera", f"127.0.0.1:{rtsp_camera.port}"),
        ],
        cwd=tmp_path,
        env=_env(),
        stdout=said,
        stderr=subprocess.PIPE,
        text=True,
        encoding="utf-8",
    )
    client = None
    try:
        client = FoxgloveClient(_url(proc))
        assert client.wait_for(lambda: client.first_advertise is not None, 10)
        assert proc.stderr is not None
        err = proc.stderr.read()
        assert proc.wait(timeout=60) == 0, err
        time.sleep(0.3)
    finally:
        if client is not None:
            client.close()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        said.close()
    # the camera's channels are there from the start, before any frame came
    first = {c["topic"]: c["schemaName"] for c in client.first_advertise or []}
    for topic, schema in CAMERA_CHANNELS.items():
        assert first.get(topic) == schema, topic
    # every frame, thumbnail and overlay of the file reached the viewer, the very same bytes
    channels, messages = recorded(out)
    got = client.by_topic()
    for topic in CAMERA_CHANNELS:
        assert messages[topic], topic
        assert got.get(topic) == messages[topic], (topic, len(got.get(topic, [])))
        assert client.channels_by_topic()[topic]["schema"] == channels[topic]["schema"]
    assert len(messages["/camera/main"]) > 100  # about 30 frames a second for 8 s
    served = (tmp_path / "said.txt").read_text(encoding="utf-8")
    assert "foxglove: served" in served and "dropped" not in served
    overlay = json.loads(got["/camera/main/annotations"][-1][1])
    assert overlay["texts"][0]["text"].startswith("P ")
