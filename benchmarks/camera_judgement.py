"""Camera judgement benchmark: the cost per judged command, on a long 1080p recording.

A simulated flight of --minutes (default 10) is recorded offline with the simulated
camera's main stream encoded at --size (default 1920x1080) and --fps (default 25), a
keyframe every 2 s as cameras send them, and a zoom command every 30 s (zoom_in_2x, then
zoom_out_2x), the aircraft orbiting and the gimbal looking 45 deg down. The recording is
kept in --dir and made again only when missing (making 10 minutes at 1080p takes minutes).

Measured on it, in the same run:

* reference: decoding the whole main stream with PyAV (what judging by decoding every
  frame would cost at least);
* analyze without the camera judgement (the telemetry's share);
* analyze with it: the extra time per judged command, the frames it decoded, and the
  ratio of its cost to the whole-stream decode.

    python benchmarks/camera_judgement.py --minutes 10
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import time
from pathlib import Path
from typing import cast

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import av

from analyzer.analysis.camera import hook
from analyzer.analysis.camera.source import RecordingVideo
from analyzer.cli import main
from analyzer.mcapio.read.reader import McapRecording
from analyzer.mcapio.read.video_window import parse_frame
from analyzer.mcapio.write.video import ROLE_VIDEO
from analyzer.sim.camera.offline import record_offline
from analyzer.sim.engine import SimConfig
from analyzer.sim.ground import Step

EVERY_S = 30.0


def flight(minutes: float) -> tuple[tuple[Step, ...], float]:
    duration = minutes * 60.0
    steps = [Step(1.0, "specified_angle", {"pitch_deg": -45})]
    at = 20.0
    zoom_in = True
    while at < duration - 8.0:
        action = "zoom_in_2x" if zoom_in else "zoom_out_2x"
        steps.append(Step(at, "zoom", {"action": action}))
        zoom_in = not zoom_in
        at += EVERY_S
    return tuple(steps), duration


def make(path: Path, minutes: float, size: tuple[int, int], fps: int) -> int:
    steps, duration = flight(minutes)
    if path.exists():
        print(f"recording: {path} (kept from an earlier run)")
        return len(steps) - 1
    started = time.perf_counter()
    record_offline(
        path, steps, duration, SimConfig(uav=True), fps=fps, encoded=size, gop_s=2.0,
        thumbnail_interval=0.0,
    )  # fmt: skip
    print(f"recording: {path} made in {time.perf_counter() - started:.0f} s")
    return len(steps) - 1


def decode_everything(path: Path) -> tuple[int, float]:
    """Every frame of /camera/main decoded (not converted): frames, seconds."""
    started = time.perf_counter()
    decoder = cast(av.VideoCodecContext, av.CodecContext.create("h264", "r"))
    decoder.thread_type = "SLICE"
    frames = 0
    for message in McapRecording(path).messages(topics={"/camera/main"}, roles={ROLE_VIDEO}):
        frame = parse_frame(message.data)
        if frame is not None:
            frames += len(decoder.decode(av.Packet(frame.data)))
    frames += len(decoder.decode(None))
    return frames, time.perf_counter() - started


def analyze(path: Path, *, camera: bool) -> tuple[float, int, int]:
    """``analyze --json`` of the recording: seconds, camera findings, frames the camera
    judgement decoded."""
    made: list[RecordingVideo] = []
    original = hook.recording_video

    def tracked(file: str | Path) -> RecordingVideo | None:
        video = original(file) if camera else None
        if video is not None:
            made.append(video)
        return video

    hook.recording_video = tracked  # type: ignore[assignment]
    out = io.StringIO()
    started = time.perf_counter()
    try:
        with contextlib.redirect_stdout(out):
            assert main(["analyze", str(path), "--json", "-q"]) == 0
    finally:
        hook.recording_video = original
    seconds = time.perf_counter() - started
    judged = out.getvalue().count('"check": "picture"')
    return seconds, judged, sum(v.frames_decoded for v in made)


def main_benchmark() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--size", default="1920x1080")
    parser.add_argument("--fps", type=int, default=25)
    parser.add_argument("--dir", default="/tmp/gimbal-camera-bench")
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    folder = Path(args.dir)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"flight-{args.minutes:g}min-{args.size}-{args.fps}fps.mcap"
    commands = make(path, args.minutes, (width, height), args.fps)
    size_mb = path.stat().st_size / 1e6
    frames, decode_s = decode_everything(path)
    plain_s, _, _ = analyze(path, camera=False)
    judged_s, judged, decoded = analyze(path, camera=True)
    extra = judged_s - plain_s
    print(f"{args.minutes:g} min at {args.size}, {args.fps} fps: {size_mb:.0f} MB, {frames} frames")
    print(f"  {'reference: the whole stream decoded':<44}{decode_s:7.1f} s")
    print(f"  {'analyze without the camera judgement':<44}{plain_s:7.1f} s")
    print(f"  {f'analyze with it ({judged} of {commands} commands judged)':<44}{judged_s:7.1f} s")
    print(
        f"  per judged command: {extra / max(judged, 1):.2f} s, {decoded / max(judged, 1):.0f} "
        f"frames decoded ({decoded / max(frames, 1) * 100:.1f} % of the stream in all)"
    )
    print(f"  camera judgement / whole-stream decode: {extra / decode_s:.2f}")


if __name__ == "__main__":
    main_benchmark()
