"""A test RTSP camera: gst-rtsp-server serving H.264 at the vendor document's path, digest auth.

Runs under the system Python (``/usr/bin/python3``, which has GObject introspection), as a
subprocess of the tests and benchmarks. It serves the document's URLs
``/cam/realmonitor?channel=1&subtype=0|1|2`` with digest authentication (admin/admin by
default) on 127.0.0.1, on a free port unless ``--port`` says otherwise, and prints
``READY <port>`` once it listens; the mounts and the authentication are those of the
simulated camera's RTSP server (analyzer/sim/camera/rtsp_serve.py), a videotestsrc each.

    /usr/bin/python3 tests/rtsp_camera.py --size 640x360 --fps 30
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the analyzer's own server

from analyzer.sim.camera.rtsp_serve import (
    SUBTYPES,
    GLib,
    Gst,
    factory,
    mount_path,
    server_with_digest,
)

PATTERNS = {"0": "ball", "1": "smpte", "2": "pinwheel"}


def launch_line(args: argparse.Namespace, subtype: str) -> str:
    width, height = (int(v) for v in args.size.split("x"))
    if args.bframes:
        encoder = (
            f"x264enc speed-preset=ultrafast bframes={args.bframes} b-adapt=false "
            f"key-int-max={args.gop} bitrate={args.bitrate}"
        )
    else:
        encoder = (
            f"x264enc tune=zerolatency speed-preset=ultrafast key-int-max={args.gop} "
            f"bitrate={args.bitrate}"
        )
    if args.config_interval == 0:  # parameter sets only in the SDP, as some cameras do
        encoder += " option-string=repeat-headers=0"
    coded = f"{encoder} ! video/x-h264,profile=high ! rtph264pay"
    if args.codec == "h265":
        coded = (
            f"x265enc tune=zerolatency speed-preset=ultrafast key-int-max={args.gop} "
            f"bitrate={args.bitrate} ! video/x-h265 ! rtph265pay"
        )
    return (
        f"( videotestsrc is-live=true pattern={args.pattern or PATTERNS[subtype]} "
        f"! video/x-raw,width={width},height={height},framerate={args.fps}/1 "
        '! timeoverlay font-desc="Sans 24" ! videoconvert '
        f"! {coded} name=pay0 pt=96 config-interval={args.config_interval} )"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--port", default="0", help="TCP port (default: a free one)")
    parser.add_argument("--size", default="640x360")
    parser.add_argument("--codec", choices=("h264", "h265"), default="h264")
    parser.add_argument("--fps", type=int, default=30)
    parser.add_argument("--gop", type=int, default=30, help="frames from keyframe to keyframe")
    parser.add_argument("--bitrate", type=int, default=800, help="kbit/s")
    parser.add_argument("--bframes", type=int, default=0, help="B-frames (a camera that has them)")
    parser.add_argument(
        "--config-interval",
        type=int,
        default=-1,
        help="SPS/PPS in the stream: -1 before every keyframe (default), 0 only in the SDP",
    )
    parser.add_argument("--pattern", default="", help="videotestsrc pattern of every stream")
    parser.add_argument("--user", default="admin")
    parser.add_argument("--password", default="admin")
    args = parser.parse_args()

    Gst.init(None)
    server, mounts = server_with_digest("127.0.0.1", args.port, args.user, args.password)
    for subtype in SUBTYPES:
        mounts.add_factory(mount_path(subtype), factory(launch_line(args, subtype)))

    if server.attach(None) == 0:
        print(f"cannot listen on 127.0.0.1:{args.port}", file=sys.stderr)
        return 1
    print(f"READY {server.get_bound_port()}", flush=True)
    GLib.MainLoop().run()
    return 0


if __name__ == "__main__":
    sys.exit(main())
