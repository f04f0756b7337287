"""Video passthrough benchmark: a 1080p30 RTSP stream recorded vs a bare PyAV demux loop.

The test camera (tests/rtsp_camera.py, gst-rtsp-server under the system Python) serves
1920x1080 H.264 at 30 fps (moving picture, running clock: every frame differs). Two
clients read the same shared stream at the same time, for the same seconds:

* reference: a bare PyAV loop, ``av.open`` + ``for packet in demux(): bytes(packet)``;
* recorder: what ``record --video main`` runs: the VideoStream thread (demux, access units,
  Annex B, capture times, a JPEG thumbnail every 2 s) and the VideoRecorder writing into an
  McapSink every 50 ms (base64 JSON, chunks, zstd, flush every 0.5 s).

CPU time is measured per thread (/proc/self/task/TID/stat), so the camera process and the
other client do not count. Printed: frames, CPU % of one core of each side, and their
ratio. Issue 23's goal: the recorder costs a few percent of one core.

    python benchmarks/video_passthrough.py --seconds 20
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import av

from analyzer.mcapio.write.sink import McapSink
from analyzer.mcapio.write.video import VideoRecorder
from analyzer.pipeline import Batch
from analyzer.video.rtsp_stream import VideoStream
from analyzer.video.spec import parse_video_spec

ROOT = Path(__file__).resolve().parents[1]
TICKS = os.sysconf("SC_CLK_TCK")


def thread_cpu_s(tid: int) -> float:
    """User + system CPU seconds of one thread of this process."""
    try:
        fields = (
            Path(f"/proc/self/task/{tid}/stat")
            .read_text(encoding="utf-8")
            .rsplit(")", 1)[1]
            .split()
        )
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / TICKS


def start_camera(
    size: str, fps: int, bitrate: int, pattern: str
) -> tuple[subprocess.Popen[str], int]:
    camera = subprocess.Popen(
        [
            "/usr/bin/python3", str(ROOT / "tests" / "rtsp_camera.py"), "--size", size,
            "--fps", str(fps), "--bitrate", str(bitrate), "--gop", str(fps), "--pattern", pattern,
        ],
        stdout=subprocess.PIPE,
        text=True, encoding="utf-8",
    )  # fmt: skip
    assert camera.stdout is not None
    line = camera.stdout.readline()
    if not line.startswith("READY "):
        camera.kill()
        raise SystemExit(f"the test camera did not start: {line!r}")
    return camera, int(line.split()[1])


class BareDemux(threading.Thread):
    """The reference: PyAV's demuxer and nothing else (packets copied out as bytes)."""

    def __init__(self, url: str) -> None:
        super().__init__(name="bare-demux", daemon=True)
        self.url = url
        self.packets = 0
        self.bytes = 0
        self.stop = threading.Event()
        self.cpu_start = 0.0

    def run(self) -> None:
        container = av.open(self.url, options={"rtsp_transport": "tcp"}, timeout=(5.0, 5.0))
        try:
            for packet in container.demux(container.streams.video[0]):
                if self.stop.is_set():
                    break
                self.bytes += len(bytes(packet))
                self.packets += 1
        finally:
            container.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--size", default="1920x1080")
    parser.add_argument("--fps", type=int, default=30)
    parser.add_argument("--bitrate", type=int, default=6000, help="kbit/s of the camera")
    parser.add_argument(
        "--pattern",
        default="pinwheel",
        help="videotestsrc pattern (default pinwheel: turning, detailed, every frame differs)",
    )
    args = parser.parse_args()

    camera, port = start_camera(args.size, args.fps, args.bitrate, args.pattern)
    workdir = Path(tempfile.mkdtemp(prefix="video-bench-"))
    try:
        spec = parse_video_spec("main", camera=f"127.0.0.1:{port}")
        sink = McapSink(workdir / "bench.mcap", metadata={"source": "benchmark"})
        stream = VideoStream(spec)
        recorder = VideoRecorder(sink, [stream])
        bare = BareDemux(spec.url)
        recorder.start()
        # One client at a time into the shared media: gst-rtsp-server 1.22 can abort when a
        # second client joins while the first one's media is still being prepared.
        deadline = time.monotonic() + 15
        while stream.state != "connected" and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.5)
        bare.start()
        written = {"frames": 0}
        writer_tid: list[int] = []
        done = threading.Event()

        def drive() -> None:  # the capture thread's part: a batch every 50 ms
            writer_tid.append(threading.get_native_id())
            while not done.wait(0.05):
                recorder.stage.process([])
                recorder.handle(Batch())
            written["frames"] = recorder.frames_written

        driver = threading.Thread(target=drive, name="driver", daemon=True)
        driver.start()
        time.sleep(3.0)  # both connected and past the opening burst
        threads = {t.name: t.native_id for t in threading.enumerate() if t.native_id}
        if f"video-{spec.name}" not in threads:
            raise SystemExit(f"the recorder stopped: {stream.last_problem or stream.state}")
        recorder_tids = [threads[f"video-{spec.name}"], writer_tid[0], threads["mcap-flush"]]
        if "bare-demux" not in threads:
            raise SystemExit("the bare demux client could not connect to the test camera")
        bare_tid = threads["bare-demux"]
        frames0, packets0 = recorder.frames_written, bare.packets
        cpu0 = (sum(thread_cpu_s(t) for t in recorder_tids), thread_cpu_s(bare_tid))
        wall0 = time.monotonic()
        time.sleep(args.seconds)
        cpu1 = (sum(thread_cpu_s(t) for t in recorder_tids), thread_cpu_s(bare_tid))
        wall = time.monotonic() - wall0
        frames, packets = recorder.frames_written - frames0, bare.packets - packets0
        done.set()
        driver.join()
        bare.stop.set()
        recorder.stop()
        sink.close()
        size = (workdir / "bench.mcap").stat().st_size
    finally:
        camera.terminate()
        camera.wait(10)
    recorder_pct = 100 * (cpu1[0] - cpu0[0]) / wall
    bare_pct = 100 * (cpu1[1] - cpu0[1]) / wall
    print(
        f"camera: {args.size} at {args.fps} fps, {args.bitrate} kbit/s, pattern {args.pattern}, "
        f"{wall:.1f} s measured"
    )
    print(f"bare PyAV demux loop : {packets:6d} packets  {bare_pct:5.1f} % of one core")
    print(
        f"record --video main  : {frames:6d} frames   {recorder_pct:5.1f} % of one core "
        f"(demux, access units, thumbnails, MCAP writing)"
    )
    ratio = recorder_pct / bare_pct if bare_pct else float("inf")
    print(f"ratio recorder / bare demux: {ratio:.2f}")
    print(f"frames per second recorded: {frames / wall:.1f} (camera: {args.fps})")
    print(f"recording: {size / 1e6:.1f} MB, {8 * size / 1e6 / (wall + 3):.1f} Mbit/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
