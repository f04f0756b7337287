"""What the writer's hold-back costs a live recording with video, against none, in one run.

A saturated CAN bus (the bus mix of ``convert_speed.py``, about 7,600 frames/s, each one
MCAP message as ``record`` writes it) and a 30 fps camera (frames of 15-25 kB of random
bytes, base64 in JSON as ``/camera/NAME`` holds them) whose frames reach the writer, in
their order, 0 to 60 ms after the telemetry of their moment; once, at the start, the 28
frames a camera sends at once when the stream opens, the first 0.9 s late (as measured
on the test camera). The writer flushes every half second of log time with a
provisional summary, as a live recording does. Each side (hold-back 0 and
``VIDEO_HOLD_BACK_S``) runs several times, interleaved; the best time counts. It prints
the writer's share of one core per second recorded and how many messages it had to log
later than their own time.

  python benchmarks/hold_back_cost.py [--seconds 20] [--repeat 3]
"""

from __future__ import annotations

import argparse
import base64
import io
import json
import random
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from convert_speed import make_frames  # noqa: E402

from analyzer.mcapio.channels import can_frame_json  # noqa: E402
from analyzer.mcapio.log_time import time_ns  # noqa: E402
from analyzer.mcapio.write.chunked_writer import ChunkedWriter  # noqa: E402
from analyzer.video.spec import VIDEO_HOLD_BACK_S  # noqa: E402

S = 1_000_000_000
FPS = 30
BURST = 28
BURST_LATE = 0.9
FLUSH_S = 0.5

# (arrival time ns, log time ns, channel index, data) in arrival order
Arrival = tuple[int, int, int, bytes]


def traffic(seconds: float) -> list[Arrival]:
    rng = random.Random(7)
    frames = make_frames(int(seconds * 7600))
    t0 = time_ns(frames[0].time)
    out: list[Arrival] = [(time_ns(f.time), time_ns(f.time), 0, can_frame_json(f)) for f in frames]
    end = out[-1][0]
    n = arrival = 0
    while (t := t0 + n * S // FPS) < end:
        picture = rng.randbytes(rng.randint(15_000, 25_000))
        message = {
            "timestamp": {"sec": t // S, "nsec": t % S},
            "frame_id": "camera_main",
            "data": base64.b64encode(picture).decode(),
            "format": "h264",
        }
        # the burst the camera had buffered comes at once, its first frame 0.9 s late; a
        # stream's frames come in their order
        late = int(rng.uniform(0, 0.06) * S)
        arrival = max(arrival, t0 + int(BURST_LATE * S) if n < BURST else t + late)
        out.append((arrival, t, 1, json.dumps(message).encode()))
        n += 1
    out.sort(key=lambda a: a[0])
    return out


def record(arrivals: list[Arrival], hold_back: float) -> tuple[float, int]:
    """Seconds the writer took and the messages it logged later than their own time."""
    writer = ChunkedWriter(io.BytesIO(), live_summary=True, hold_back=round(hold_back * S))
    writer.start("", "benchmark")
    schema = writer.register_schema("s", "jsonschema", b"{}")
    channels = [
        writer.register_channel("/can/frames", "json", schema),
        writer.register_channel("/camera/main", "json", schema),
    ]
    add = writer.add_message
    next_flush = arrivals[0][0] + int(FLUSH_S * S)
    started = time.perf_counter()
    for sequence, (arrival, log_time, channel, data) in enumerate(arrivals):
        if arrival >= next_flush:
            writer.flush()
            next_flush += int(FLUSH_S * S)
        add(channels[channel], log_time, data, log_time, sequence)
    writer.finish()
    return time.perf_counter() - started, writer.retimed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    arrivals = traffic(args.seconds)
    video = sum(1 for a in arrivals if a[2] == 1)
    print(
        f"{args.seconds:g} s: {len(arrivals) - video} CAN frames, {video} camera frames "
        f"({sum(len(a[3]) for a in arrivals) / 1e6:.1f} MB of messages)"
    )
    best = {0.0: float("inf"), VIDEO_HOLD_BACK_S: float("inf")}
    retimed: dict[float, int] = {}
    for _ in range(args.repeat):
        for hold_back in best:
            took, retimed[hold_back] = record(arrivals, hold_back)
            best[hold_back] = min(best[hold_back], took)
    for hold_back, took in best.items():
        print(
            f"hold-back {hold_back:g} s: {took / args.seconds * 100:5.2f} % of a core, "
            f"{retimed[hold_back]} messages logged later than their own time"
        )
    ratio = best[VIDEO_HOLD_BACK_S] / best[0.0]
    print(f"ratio hold-back {VIDEO_HOLD_BACK_S:g} s / none: {ratio:.2f}")
    print(f"best of {args.repeat} runs each, interleaved; zstd chunks, a flush every {FLUSH_S} s")


if __name__ == "__main__":
    main()
