"""The simulated camera over RTSP: access units from standard input, served by GStreamer.

A standalone program for a Python with GObject introspection and GStreamer's RTSP server
(Debian: /usr/bin/python3 with python3-gi, gir1.2-gst-rtsp-server-1.0, gstreamer1.0-rtsp
and the good / bad plugins); it imports nothing of the analyzer. It serves the vendor
document's paths ``/cam/realmonitor?channel=1&subtype=0|1|2`` on 127.0.0.1 (or --host)
with digest authentication, and prints ``READY <port>`` once it listens. Standard input
carries the pictures: for each, one byte of subtype, four bytes of length (big endian)
and the H.264 access unit in Annex B; it ends with the input.

gst-rtsp-server matches mounts on the path alone, so ``QueryMounts`` turns the query
into path segments (``/cam/realmonitor/channel=1/subtype=0``); each subtype is its own
stream. The tests' RTSP camera uses the same mounts and authentication.
"""

from __future__ import annotations

import argparse
import struct
import sys
import threading
from typing import Any

import gi

gi.require_version("Gst", "1.0")
gi.require_version("GstRtsp", "1.0")
gi.require_version("GstRtspServer", "1.0")
from gi.repository import GLib, Gst, GstRtsp, GstRtspServer  # noqa: E402

PATH = "/cam/realmonitor"
SUBTYPES = ("0", "1", "2")
HEADER = struct.Struct(">BI")  # subtype, length
LAUNCH = (
    "( appsrc name=src is-live=true do-timestamp=true format=time "
    "caps=video/x-h264,stream-format=byte-stream,alignment=au "
    "! h264parse ! rtph264pay name=pay0 pt=96 config-interval=-1 )"
)


class QueryMounts(GstRtspServer.RTSPMountPoints):
    """Mount points whose paths include the URL's query, one segment per parameter."""

    def do_make_path(self, url: Any) -> str:
        path: str = url.abspath
        if url.query:
            path += "/" + "/".join(sorted(url.query.split("&")))
        return path


def mount_path(subtype: str) -> str:
    return f"{PATH}/channel=1/subtype={subtype}"


def server_with_digest(host: str, port: str, user: str, password: str) -> tuple[Any, Any]:
    """An RTSP server on ``host:port`` (port "0": a free one) whose streams need ``user``
    and ``password`` (digest), and its mount points."""
    server = GstRtspServer.RTSPServer()
    server.set_address(host)
    server.set_service(port)
    mounts = QueryMounts()
    server.set_mount_points(mounts)
    auth = GstRtspServer.RTSPAuth()
    auth.set_supported_methods(GstRtsp.RTSPAuthMethod.DIGEST)
    token = GstRtspServer.RTSPToken.new()
    token.set_string(GstRtspServer.RTSP_TOKEN_MEDIA_FACTORY_ROLE, "user")
    auth.add_digest(user, password, token)
    server.set_auth(auth)
    return server, mounts


def factory(launch: str) -> Any:
    """A shared media factory of a launch line that the digest user may watch."""
    made = GstRtspServer.RTSPMediaFactory()
    made.set_launch(launch)
    made.set_shared(True)
    made.add_role_from_structure(
        Gst.Structure.new_from_string(
            "user, media.factory.access=(boolean)true, media.factory.construct=(boolean)true"
        )
    )
    return made


class Feeds:
    """The appsrc of each subtype's stream while it is being watched."""

    def __init__(self) -> None:
        self.sources: dict[int, Any] = {}
        self.lock = threading.Lock()

    def configured(self, subtype: int) -> Any:
        def on_configure(_: Any, media: Any) -> None:
            source = media.get_element().get_child_by_name("src")
            with self.lock:
                self.sources[subtype] = source
            media.connect("unprepared", lambda *_: self._gone(subtype, source))

        return on_configure

    def _gone(self, subtype: int, source: Any) -> None:
        with self.lock:
            if self.sources.get(subtype) is source:
                del self.sources[subtype]

    def push(self, subtype: int, data: bytes) -> None:
        with self.lock:
            source = self.sources.get(subtype)
        if source is not None:  # nobody watching: the picture is dropped
            source.emit("push-buffer", Gst.Buffer.new_wrapped(data))


def read_input(feeds: Feeds, loop: Any) -> None:
    """Pictures from standard input until it ends; then the server stops."""
    stream = sys.stdin.buffer
    while True:
        head = stream.read(HEADER.size)
        if len(head) < HEADER.size:
            break
        subtype, size = HEADER.unpack(head)
        data = stream.read(size)
        if len(data) < size:
            break
        feeds.push(subtype, data)
    GLib.idle_add(loop.quit)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", default="0", help="TCP port (default: a free one)")
    parser.add_argument("--user", default="admin")
    parser.add_argument("--password", default="admin")
    args = parser.parse_args()
    Gst.init(None)
    server, mounts = server_with_digest(args.host, args.port, args.user, args.password)
    feeds = Feeds()
    for subtype in SUBTYPES:
        made = factory(LAUNCH)
        made.connect("media-configure", feeds.configured(int(subtype)))
        mounts.add_factory(mount_path(subtype), made)
    if server.attach(None) == 0:
        print(f"cannot listen on {args.host}:{args.port}", file=sys.stderr)
        return 1
    loop = GLib.MainLoop()
    threading.Thread(target=read_input, args=(feeds, loop), daemon=True).start()
    print(f"READY {server.get_bound_port()}", flush=True)
    loop.run()
    return 0


if __name__ == "__main__":
    sys.exit(main())
