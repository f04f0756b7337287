"""A test RTSP camera: gst-rtsp-server serving H.264 at the vendor document's path, digest auth.

Runs under the system Python (``/usr/bin/python3``, which has GObject introspection), as a
subprocess of the tests and benchmarks. It serves the document's URLs
``/cam/realmonitor?channel=1&subtype=0|1|2`` with digest authentication (admin/admin by
default) on 127.0.0.1, on a free port unless ``--port`` says otherwise, and prints
``READY <port>`` once it listens. gst-rtsp-server matches mounts on the path alone, so a
``RTSPMountPoints`` subclass turns the query into path segments
(``/cam/realmonitor/channel=1/subtype=0``); each subtype is its own stream.

    /usr/bin/python3 tests/rtsp_camera.py --size 640x360 --fps 30
"""

from __future__ import annotations

import argparse
import sys

import gi

gi.require_version("Gst", "1.0")
gi.require_version("GstRtsp", "1.0")
gi.require_version("GstRtspServer", "1.0")
from gi.repository import GLib, Gst, GstRtsp, GstRtspServer  # noqa: E402

PATH = "/cam/realmonitor"
SUBTYPES = ("0", "1", "2")
PATTERNS = {"0": "ball", "1": "smpte", "2": "pinwheel"}


class QueryMounts(GstRtspServer.RTSPMountPoints):
    """Mount points whose paths include the URL's query, one segment per parameter."""

    def do_make_path(self, url: GstRtspServer.RTSPUrl) -> str:
        path = url.abspath
        if url.query:
            path += "/" + "/".join(sorted(url.query.split("&")))
        return path


def mount_path(subtype: str) -> str:
    return f"{PATH}/channel=1/subtype={subtype}"


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
    server = GstRtspServer.RTSPServer()
    server.set_address("127.0.0.1")
    server.set_service(args.port)
    mounts = QueryMounts()
    server.set_mount_points(mounts)

    auth = GstRtspServer.RTSPAuth()
    auth.set_supported_methods(GstRtsp.RTSPAuthMethod.DIGEST)
    token = GstRtspServer.RTSPToken.new()
    token.set_string(GstRtspServer.RTSP_TOKEN_MEDIA_FACTORY_ROLE, "user")
    auth.add_digest(args.user, args.password, token)
    server.set_auth(auth)

    for subtype in SUBTYPES:
        factory = GstRtspServer.RTSPMediaFactory()
        factory.set_launch(launch_line(args, subtype))
        factory.set_shared(True)
        factory.add_role_from_structure(
            Gst.Structure.new_from_string(
                "user, media.factory.access=(boolean)true, media.factory.construct=(boolean)true"
            )
        )
        mounts.add_factory(mount_path(subtype), factory)

    if server.attach(None) == 0:
        print(f"cannot listen on 127.0.0.1:{args.port}", file=sys.stderr)
        return 1
    print(f"READY {server.get_bound_port()}", flush=True)
    GLib.MainLoop().run()
    return 0


if __name__ == "__main__":
    sys.exit(main())
