"""`record --video`: a real RTSP camera (gst-rtsp-server) recorded next to a simulated gimbal."""

from __future__ import annotations

import base64
import itertools
import json
import os
import re
import signal
import socket
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import av
import jsonschema
import pytest
from mcap.reader import make_reader

from analyzer.mcapio.read.reader import McapRecording
from analyzer.mcapio.write.video import COMPRESSED_IMAGE_SCHEMA, COMPRESSED_VIDEO_SCHEMA
from analyzer.video.annexb import H264_IDR, H264_SPS, nal_type, split_nals
from analyzer.video.spec import VIDEO_HOLD_BACK_S
from tests.mcap_doctor import examine
from tests.platforms import posix_signals

pytestmark = pytest.mark.slow  # a real RTSP camera

ROOT = Path(__file__).resolve().parent.parent
FRAME_INTERVAL = 1 / 30


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _env() -> dict[str, str]:
    return dict(os.environ, PYTHONDONTWRITEBYTECODE="1", PYTHONPATH=str(ROOT))


@contextmanager
def gimbal() -> Iterator[int]:
    """The simulated gimbal on a loopback TCP port (attitude feedback every 500 ms)."""
    port = free_port()
    args = ["simulate", "--on", f"tcp:127.0.0.1:{port}", "--quiet", "--duration", "60"]
    process = subprocess.Popen(
        [sys.executable, "-m", "analyzer", *args], env=_env(), stdout=subprocess.DEVNULL
    )
    try:
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            try:
                socket.create_connection(("127.0.0.1", port), 0.2).close()
                break
            except OSError:
                time.sleep(0.05)
        yield port
    finally:
        process.terminate()
        process.wait(10)


def record(args: list[str], cwd: Path, **kwargs: Any) -> subprocess.CompletedProcess[str]:
    kwargs.setdefault("env", _env())
    return subprocess.run(
        [sys.executable, "-m", "analyzer", "record", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=90,
        **kwargs,
    )


def record_camera(
    camera_port: int, out: Path, cwd: Path, *extra: str, **kwargs: Any
) -> subprocess.CompletedProcess[str]:
    """``record`` of the simulated gimbal on TCP with the test camera's main stream."""
    with gimbal() as port:
        return record(
            [
                "--source", f"tcp:127.0.0.1:{port}", "-o", str(out),
                "--video", "main", "--camera", f"127.0.0.1:{camera_port}", *extra,
            ],
            cwd,
            **kwargs,
        )  # fmt: skip


def messages(path: Path) -> dict[str, list[tuple[int, dict[str, Any]]]]:
    """Every message by topic (log time ns, JSON), read with the mcap library."""
    out: dict[str, list[tuple[int, dict[str, Any]]]] = {}
    with path.open("rb") as f:
        for _, channel, message in make_reader(f).iter_messages():
            out.setdefault(channel.topic, []).append((message.log_time, json.loads(message.data)))
    return out


def decode_all(frames: list[dict[str, Any]]) -> int:
    """Pictures PyAV decodes from the messages, fed one message per packet as a player does."""
    decoder = av.CodecContext.create({"h264": "h264", "h265": "hevc"}[frames[0]["format"]], "r")
    decoded = 0
    for frame in frames:
        decoded += len(decoder.decode(av.Packet(base64.b64decode(frame["data"]))))
    return decoded + len(decoder.decode(None))


def assert_logged_at_capture_time(
    path: Path, found: dict[str, list[tuple[int, dict[str, Any]]]]
) -> None:
    """Every camera message's log time is its ``timestamp`` (capture time) to the ns, and
    the file is in log-time order as `mcap doctor` checks it."""
    camera = [topic for topic in found if topic.startswith("/camera/")]
    assert camera
    for topic in camera:
        for log_time, message in found[topic]:
            # an overlay's shapes each carry the time of the feedback or command drawn
            shapes = [s for kind in ("circles", "points", "texts") for s in message.get(kind, [])]
            for stamp in [s["timestamp"] for s in shapes] or [message["timestamp"]]:
                assert log_time == stamp["sec"] * 1_000_000_000 + stamp["nsec"], topic
    diagnosis = examine(path)
    assert diagnosis.errors == [] and diagnosis.warnings == []


def info_of(path: Path, *options: str) -> str:
    """``gimbal-analyzer info`` of a recording (stdout; exit 0 checked)."""
    done = subprocess.run(
        [sys.executable, "-m", "analyzer", "info", *options, str(path)],
        env=_env(), capture_output=True, text=True, timeout=60, encoding="utf-8",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return done.stdout


def camera_diagnostics(found: dict[str, list[tuple[int, dict[str, Any]]]]) -> list[dict[str, Any]]:
    return [m for _, m in found.get("/diagnostics", []) if m["source"] == "camera/main"]


def test_record_video_decodes_back_completely_and_lines_up_with_the_telemetry(
    rtsp_camera: Any, tmp_path: Path
) -> None:
    out = tmp_path / "flight.mcap"
    done = record_camera(rtsp_camera.port, out, tmp_path, "--duration", "6")
    assert done.returncode == 0, done.stderr
    assert "/camera/main: " in done.stderr
    found = messages(out)
    video = [m for _, m in found["/camera/main"]]
    assert len(video) > 90  # 6 s at 30 fps, less the opening
    for message in video:
        jsonschema.validate(message, COMPRESSED_VIDEO_SCHEMA)
        assert message["format"] == "h264" and message["frame_id"] == "camera_main"
    first = [nal_type("h264", u) for u in split_nals(base64.b64decode(video[0]["data"]))]
    assert first.index(H264_SPS) < first.index(H264_IDR)  # a keyframe with its SPS first
    assert decode_all(video) == len(video)  # every message is exactly one picture

    # capture times: the stream's spacing, on the telemetry's clock
    stamps = [m["timestamp"]["sec"] + m["timestamp"]["nsec"] / 1e9 for m in video]
    steps = [b - a for a, b in itertools.pairwise(stamps)]
    assert statistics.median(steps) == pytest.approx(FRAME_INTERVAL, abs=0.002)
    assert max(steps) < 4 * FRAME_INTERVAL and min(steps) > 0
    # Foxglove plays by log time: it is the capture time of every frame, the burst of
    # frames the camera had buffered when the stream opened included (the writer's
    # hold-back), and the file is in log-time order all the same.
    assert_logged_at_capture_time(out, found)
    attitude = [t / 1e9 for t, _ in found["/gimbal/attitude"]]
    assert len(attitude) >= 8
    overlap = min(attitude[-1], stamps[-1]) - max(attitude[0], stamps[0])
    assert overlap > 3.0  # both cover the same seconds of the run

    thumbnails = [m for _, m in found["/camera/main/thumbnail"]]
    assert 2 <= len(thumbnails) <= 4  # one every 2 s
    for message in thumbnails:
        jsonschema.validate(message, COMPRESSED_IMAGE_SCHEMA)
        jpeg = base64.b64decode(message["data"])
        picture = av.CodecContext.create("mjpeg", "r").decode(av.Packet(jpeg))[0]
        assert (picture.width, picture.height) == (320, 180)

    info = subprocess.run(
        [sys.executable, "-m", "analyzer", "info", str(out)],
        env=_env(),
        capture_output=True,
        text=True,
        timeout=60,
        encoding="utf-8",
    )
    assert info.returncode == 0, info.stderr
    assert "video streams" in info.stdout
    listed = info.stdout.split("video streams")[1]
    line = next(x for x in listed.splitlines() if x.strip().startswith("/camera/main "))
    assert "h264 640x360" in line and f"{len(video)} frames" in line and "0 gaps" in line
    as_json = subprocess.run(
        [sys.executable, "-m", "analyzer", "info", "--json", str(out)],
        env=_env(), capture_output=True, text=True, timeout=60, encoding="utf-8",
    )  # fmt: skip
    (stream,) = json.loads(as_json.stdout)["video_streams"]
    assert stream["topic"] == "/camera/main" and stream["frames"] == len(video)
    assert stream["fps"] == pytest.approx(30, abs=0.5) and stream["gaps"] == []


def test_wrong_password_is_401_in_words_and_the_telemetry_goes_on(
    rtsp_camera: Any, tmp_path: Path
) -> None:
    out = tmp_path / "flight.mcap"
    done = record_camera(
        rtsp_camera.port, out, tmp_path, "--duration", "3", "--camera-password", "s3cr3t-x"
    )
    assert done.returncode == 1, done.stderr  # a stream asked for that never delivered
    assert "401 unauthorized: wrong user name or password" in done.stderr
    assert (
        f"gimbal-analyzer record: the video stream /camera/main (rtsp://admin@127.0.0.1:"
        f"{rtsp_camera.port}/cam/realmonitor?channel=1&subtype=0) delivered no frame"
    ) in done.stderr
    listed = info_of(out)
    assert re.search(r"/camera/main\s+requested \(rtsp://admin@127.0.0.1:\d+/.*\), failed", listed)
    (stream,) = json.loads(info_of(out, "--json"))["video_streams"]
    assert stream["failed"] is True and stream["frames"] == 0
    found = messages(out)
    assert len(found["/gimbal/attitude"]) >= 4  # the recording of the gimbal went on
    assert "/camera/main" not in found
    camera = camera_diagnostics(found)
    failed = [m for m in camera if m["state"] == "connect_failed"]
    assert failed and "401 unauthorized" in failed[0]["detail"]
    assert "s3cr3t-x" not in json.dumps(camera)  # the password is never written down
    retries = [m["retry_in_s"] for m in camera if m["state"] == "reconnecting"]
    assert retries[:3] == [0.5, 1.0, 2.0]  # the backoff of tcp:


def test_a_dropped_stream_is_a_link_diagnostic_and_comes_back_at_a_keyframe(
    rtsp_camera_factory: Callable[..., Any], tmp_path: Path
) -> None:
    camera = rtsp_camera_factory()
    out = tmp_path / "flight.mcap"
    with gimbal() as port:
        recorder = subprocess.Popen(
            [
                sys.executable, "-m", "analyzer", "record", "--source", f"tcp:127.0.0.1:{port}",
                "-o", str(out), "--duration", "9", "--video", "main",
                "--camera", f"127.0.0.1:{camera.port}",
            ],
            cwd=tmp_path, env=_env(), stderr=subprocess.PIPE, text=True, encoding="utf-8",
        )  # fmt: skip
        time.sleep(4)
        camera.kill()  # power cut: no teardown, the link just drops
        killed_at = time.time()
        time.sleep(1)
        rtsp_camera_factory("--port", str(camera.port))  # the camera is back
        _, err = recorder.communicate(timeout=60)
    assert recorder.returncode == 0, err
    found = messages(out)
    (stream,) = json.loads(info_of(out, "--json"))["video_streams"]
    assert len(stream["gaps"]) == 1  # the outage
    assert stream["fps"] == pytest.approx(30, abs=1.0)  # over the time it was connected
    states = [m["state"] for m in camera_diagnostics(found)]
    assert states[:2] == ["connecting", "connected"]
    lost = states.index("lost")
    assert "reconnecting" in states[lost:] and "connected" in states[lost + 1 :]
    attitude = [t / 1e9 for t, _ in found["/gimbal/attitude"]]
    assert any(t > killed_at + 1 for t in attitude)  # telemetry never stopped
    video = found["/camera/main"]
    times = [t / 1e9 for t, _ in video]
    gap = max(range(1, len(times)), key=lambda i: times[i] - times[i - 1])
    assert times[gap] - times[gap - 1] > 1.0 and times[gap] > killed_at
    resumed = base64.b64decode(video[gap][1]["data"])
    assert H264_IDR in [nal_type("h264", u) for u in split_nals(resumed)]
    assert decode_all([m for _, m in video]) == len(video)
    assert_logged_at_capture_time(out, found)  # the burst after reconnecting too


def test_a_stream_with_b_frames_is_refused_in_words(
    rtsp_camera_factory: Callable[..., Any], tmp_path: Path
) -> None:
    camera = rtsp_camera_factory("--bframes", "2")
    out = tmp_path / "flight.mcap"
    done = record_camera(camera.port, out, tmp_path, "--duration", "3")
    assert done.returncode == 1, done.stderr  # the stream asked for was not recorded
    assert "/camera/main (rtsp://admin@127.0.0.1:" in done.stderr
    assert "delivered no frame" in done.stderr and "B-frames" in done.stderr
    refused = [m for m in camera_diagnostics(messages(out)) if m["state"] == "refused"]
    assert len(refused) == 1 and "B-frames" in refused[0]["detail"]


def test_disk_full_with_video_stops_and_keeps_every_complete_chunk(
    rtsp_camera: Any, tmp_path: Path
) -> None:
    import resource

    limit = 400_000

    def limit_size() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    out = tmp_path / "flight.mcap"
    done = record_camera(rtsp_camera.port, out, tmp_path, "--duration", "20", preexec_fn=limit_size)
    assert done.returncode == 1, done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("gimbal-analyzer record: error: disk full: cannot write"), done.stderr
    assert "Traceback" not in done.stderr
    assert out.stat().st_size <= limit
    kept = int(last.split("; ")[-1].split(" messages up to ")[0])
    # Read as every command reads it: finished with a summary when the freed space
    # allowed, else the complete chunks, recovered.
    recording = McapRecording(out)
    assert sum(1 for _ in recording.messages()) == kept
    video = [json.loads(m.data) for m in recording.messages(topics={"/camera/main"})]
    assert len(video) > 10 and decode_all(video) == len(video), done.stderr
    info = subprocess.run(
        [sys.executable, "-m", "analyzer", "info", str(out)],
        env=_env(), capture_output=True, text=True, timeout=60, encoding="utf-8",
    )  # fmt: skip
    assert info.returncode == 0, info.stderr
    assert "h264 640x360" in info.stdout and f" {len(video)} frames" in info.stdout


@posix_signals
def test_ctrl_c_finishes_a_recording_with_video(rtsp_camera: Any, tmp_path: Path) -> None:
    out = tmp_path / "flight.mcap"
    with gimbal() as port:
        recorder = subprocess.Popen(
            [
                sys.executable, "-m", "analyzer", "record", "--source", f"tcp:127.0.0.1:{port}",
                "-o", str(out), "--video", "main", "--camera", f"127.0.0.1:{rtsp_camera.port}",
            ],
            cwd=tmp_path, env=_env(), stderr=subprocess.PIPE, text=True, encoding="utf-8",
        )  # fmt: skip
        time.sleep(3)
        started = time.monotonic()
        recorder.send_signal(signal.SIGINT)
        _, err = recorder.communicate(timeout=30)
    assert time.monotonic() - started < 5  # the camera thread does not hold the exit up
    assert recorder.returncode == 0, err
    video = [m for _, m in messages(out)["/camera/main"]]
    assert video and decode_all(video) == len(video)


def test_demo_records_a_bench_camera_next_to_the_simulated_gimbal(
    rtsp_camera: Any, tmp_path: Path
) -> None:
    out = tmp_path / "demo.mcap"
    done = subprocess.run(
        [
            sys.executable, "-m", "analyzer", "demo", "--no-tui", "--duration", "7",
            "--fall-short", "0.7", "-o", str(out), "--video", f"bench={rtsp_camera.url(1)}",
        ],
        cwd=tmp_path, env=_env(), capture_output=True, text=True, timeout=60, encoding="utf-8",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    found = messages(out)
    video = [m for _, m in found["/camera/bench"]]
    assert video and decode_all(video) == len(video)
    assert video[0]["frame_id"] == "camera_bench"
    assert found["/gimbal/attitude"] and found["/camera/bench/thumbnail"]
    assert_logged_at_capture_time(out, found)

    # the flight report: a strip of thumbnails, and the picture nearest each failed command
    page = tmp_path / "report.html"
    done = subprocess.run(
        [sys.executable, "-m", "analyzer", "report", str(out), "-o", str(page)],
        env=_env(), capture_output=True, text=True, timeout=60, encoding="utf-8",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    text = page.read_text(encoding="utf-8")
    section = text.split("<h2>What the camera saw</h2>")[1].split("<h2")[0]
    pictures = re.findall(r'src="data:image/jpeg;base64,([^"]+)"', section)
    strip = section.split('<div class="strip">')[1].split("</div>")[0].count("<img")
    failed = section.split('<div class="seen">')[1].count("<img")
    # falling short: the yaw and pitch targets are partial (stopped short, then still)
    assert strip == len(found["/camera/bench/thumbnail"]) and failed >= 1
    assert len(pictures) == strip + failed
    for jpeg in pictures:
        picture = av.CodecContext.create("mjpeg", "r").decode(av.Packet(base64.b64decode(jpeg)))
        assert picture[0].width == 320


def test_a_recorder_killed_with_kill_9_leaves_video_that_decodes(
    rtsp_camera: Any, tmp_path: Path
) -> None:
    out = tmp_path / "flight.mcap"
    with gimbal() as port:
        recorder = subprocess.Popen(
            [
                sys.executable, "-m", "analyzer", "record", "--source", f"tcp:127.0.0.1:{port}",
                "-o", str(out), "-q", "--video", "main", "--camera", f"127.0.0.1:{rtsp_camera.port}",
            ],
            cwd=tmp_path, env=_env(), stderr=subprocess.PIPE, text=True, encoding="utf-8",
        )  # fmt: skip
        time.sleep(5)
        recorder.kill()
        killed_at = time.time()
        recorder.communicate(timeout=30)
    recording = McapRecording(out)  # what the last 0.5 s flush left, read as every command does
    assert not recording.recovered  # the provisional summary: indexed
    video = [json.loads(m.data) for m in recording.messages(topics={"/camera/main"})]
    assert len(video) > 30 and decode_all(video) == len(video)
    assert any(True for _ in recording.messages(topics={"/gimbal/attitude"}))
    # with video the flush holds its last 2 s back: the file keeps what is older than
    # about 2.5 s (measured 2.1 to 2.7 s; some slack for a loaded machine)
    newest = max(m.log_time for m in recording.messages()) / 1e9
    assert killed_at - newest < VIDEO_HOLD_BACK_S + 1.5


def test_timestamps_that_start_over_at_a_keyframe_are_anchored_again(
    rtsp_camera: Any, tmp_path: Path
) -> None:
    # gst-rtsp-server restarts a shared live stream when a second client joins: the first
    # client's timestamps start over at a new keyframe, as with a camera whose encoder
    # restarts. Not B-frames: the recording goes on.
    out = tmp_path / "flight.mcap"
    with gimbal() as port:
        recorder = subprocess.Popen(
            [
                sys.executable, "-m", "analyzer", "record", "--source", f"tcp:127.0.0.1:{port}",
                "-o", str(out), "-q", "--duration", "7", "--video", "main",
                "--camera", f"127.0.0.1:{rtsp_camera.port}",
            ],
            cwd=tmp_path, env=_env(), stderr=subprocess.PIPE, text=True, encoding="utf-8",
        )  # fmt: skip
        time.sleep(3)
        viewer = av.open(rtsp_camera.url(0), options={"rtsp_transport": "tcp"}, timeout=5.0)
        for n, _ in enumerate(viewer.demux(viewer.streams.video[0])):
            if n > 30:
                break
        viewer.close()
        _, err = recorder.communicate(timeout=60)
    assert recorder.returncode == 0, err
    found = messages(out)
    states = [m["state"] for m in camera_diagnostics(found)]
    assert "resync" in states and "refused" not in states
    video = [m for _, m in found["/camera/main"]]
    assert decode_all(video) == len(video)
    stamps = [m["timestamp"]["sec"] + m["timestamp"]["nsec"] / 1e9 for m in video]
    steps = [b - a for a, b in itertools.pairwise(stamps)]
    assert min(steps) > 0 and max(steps) < 1.0


def test_parameter_sets_sent_only_in_the_sdp_go_in_front_of_every_keyframe(
    rtsp_camera_factory: Callable[..., Any], tmp_path: Path
) -> None:
    camera = rtsp_camera_factory("--config-interval", "0")  # SPS/PPS only in the SDP
    out = tmp_path / "flight.mcap"
    done = record_camera(camera.port, out, tmp_path, "--duration", "3")
    assert done.returncode == 0, done.stderr
    video = [m for _, m in messages(out)["/camera/main"]]
    kinds = [[nal_type("h264", u) for u in split_nals(base64.b64decode(m["data"]))] for m in video]
    keyframes = [i for i, k in enumerate(kinds) if H264_IDR in k]
    assert len(keyframes) >= 2
    for i in keyframes:
        assert kinds[i][:3] == [9, H264_SPS, 8]  # AUD, SPS, PPS, then the slices
    # a player may start at any keyframe (seeking): each decodes without what came before
    for i in keyframes:
        assert decode_all(video[i:]) == len(video) - i


def test_an_h265_camera_is_recorded_with_vps_sps_pps_before_every_keyframe(
    rtsp_camera_factory: Callable[..., Any], tmp_path: Path
) -> None:
    camera = rtsp_camera_factory("--codec", "h265")  # x265: later keyframes are bare CRAs
    out = tmp_path / "flight.mcap"
    done = record_camera(camera.port, out, tmp_path, "--duration", "3")
    assert done.returncode == 0, done.stderr
    video = [m for _, m in messages(out)["/camera/main"]]
    assert {m["format"] for m in video} == {"h265"}
    assert messages(out)["/camera/main/thumbnail"]  # decoded from an H.265 keyframe
    kinds = [[nal_type("h265", u) for u in split_nals(base64.b64decode(m["data"]))] for m in video]
    keyframes = [i for i, k in enumerate(kinds) if any(16 <= n <= 23 for n in k)]
    assert keyframes[0] == 0 and len(keyframes) >= 2
    for i in keyframes:
        assert kinds[i][:3] == [32, 33, 34]  # VPS, SPS, PPS first
    for i in keyframes:
        assert decode_all(video[i:]) == len(video) - i


def test_a_full_video_queue_drops_up_to_a_keyframe_and_says_so(rtsp_camera: Any) -> None:
    from analyzer.protocol.types import Event
    from analyzer.video.rtsp_stream import VideoFrame, VideoStream
    from analyzer.video.spec import parse_video_spec

    spec = parse_video_spec("main", camera=f"127.0.0.1:{rtsp_camera.port}")
    stream = VideoStream(spec, max_frames=10, thumbnail_interval=0)
    stream.start()
    frames: list[VideoFrame] = []
    events: list[Event] = []
    try:
        time.sleep(3)  # nobody takes the frames: the queue of 10 fills up
        for _ in range(40):
            got, news = stream.take()
            frames += got
            events += news
            time.sleep(0.05)
    finally:
        stream.stop()
    assert stream.dropped > 30
    overflow = [e for e in events if e.fields["state"] == "overflow"]
    assert len(overflow) == 1 and f"{stream.dropped} video frame(s) dropped" in str(
        overflow[0].fields["detail"]
    )
    gap = next(i for i in range(1, len(frames)) if frames[i].time - frames[i - 1].time > 0.1)
    assert gap == 10 and frames[gap].keyframe  # the queue's 10, then a keyframe
    decoded = decode_all(
        [{"format": f.codec, "data": base64.b64encode(f.data).decode()} for f in frames]
    )
    assert decoded == len(frames)


def test_two_cameras_with_their_own_passwords_from_a_file_and_a_url(
    rtsp_camera_factory: Callable[..., Any], tmp_path: Path
) -> None:
    document = rtsp_camera_factory("--password", "doc-pw")
    bench = rtsp_camera_factory("--user", "bob", "--password", "bench-pw")
    secret = tmp_path / "camera.secret"
    secret.write_text("doc-pw\n", encoding="utf-8")
    out = tmp_path / "flight.mcap"
    bench_url = bench.url(1, user="bob", password="bench-pw")
    done = record_camera(
        document.port, out, tmp_path, "--duration", "3",
        "--camera-password-file", str(secret), "--video", f"bench={bench_url}",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "unauthorized" not in done.stderr  # not "401": a port number may hold those digits
    found = messages(out)
    assert len(found["/camera/main"]) > 20 and len(found["/camera/bench"]) > 20
    everything = out.read_bytes()
    assert b"doc-pw" not in everything and b"bench-pw" not in everything
    # The same password from the environment: nothing secret on the command line.
    environ = dict(_env(), GIMBAL_CAMERA_PASSWORD="doc-pw")
    again = record_camera(
        document.port, tmp_path / "env.mcap", tmp_path, "--duration", "2", env=environ
    )
    assert again.returncode == 0, again.stderr
    assert len(messages(tmp_path / "env.mcap")["/camera/main"]) > 10


def test_a_failed_telemetry_link_with_video_says_what_the_recording_holds(
    rtsp_camera: Any, tmp_path: Path
) -> None:
    out = tmp_path / "flight.mcap"
    refused = free_port()  # nothing listens there: the telemetry link is refused
    done = record(
        [
            "--source", f"tcp:127.0.0.1:{refused}", "-o", str(out), "--duration", "3",
            "--video", "main", "--camera", f"127.0.0.1:{rtsp_camera.port}",
        ],
        tmp_path,
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    frames = len(messages(out)["/camera/main"])
    assert frames > 30
    said = re.search(
        r"holds (\d+) video frame\(s\) of /camera/main and its link diagnostics", done.stderr
    )
    assert said and int(said.group(1)) == frames, done.stderr
    assert "holds only its link diagnostics" not in done.stderr


def test_demo_with_a_camera_that_never_answers_ends_with_exit_1_and_info_lists_it(
    rtsp_camera_factory: Callable[..., Any], tmp_path: Path
) -> None:
    camera = rtsp_camera_factory()
    url = camera.url(1)
    camera.kill()  # the bench camera is off: connection refused
    out = tmp_path / "demo.mcap"
    done = subprocess.run(
        [
            sys.executable, "-m", "analyzer", "demo", "--no-tui", "--duration", "2",
            "-o", str(out), "--video", f"bench={url}",
        ],
        cwd=tmp_path, env=_env(), capture_output=True, text=True, timeout=60, encoding="utf-8",
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert "gimbal-analyzer demo: the video stream /camera/bench (rtsp://admin@" in done.stderr
    assert "delivered no frame (last link message:" in done.stderr
    assert messages(out)["/gimbal/attitude"]  # the simulated gimbal was recorded all the same
    listed = info_of(out)
    assert re.search(r"/camera/bench\s+requested \(rtsp://admin@127\.0\.0\.1:\d+/", listed)
    assert "failed: no frame recorded" in listed and "admin:admin" not in listed
