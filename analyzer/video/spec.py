"""`--video SPEC` / `--camera HOST[:PORT]`: which RTSP streams to record, by the document's name."""

from __future__ import annotations

import argparse
import os
import re
import textwrap
from dataclasses import dataclass
from urllib.parse import quote, unquote, urlsplit, urlunsplit

from analyzer.errors import UsageError
from analyzer.extras import VIDEO, require
from analyzer.protocol.types import Event

# Vendor document section 1.3: the camera's address and its RTSP streams.
DEFAULT_CAMERA = "192.168.42.108:554"
DEFAULT_RTSP_PORT = 554
DEFAULT_USER = "admin"
DEFAULT_PASSWORD = "admin"
PASSWORD_ENV = "GIMBAL_CAMERA_PASSWORD"  # the password without showing it in ps or history
DOCUMENT_PATH = "/cam/realmonitor?channel=1&subtype={subtype}"
STREAMS = {"main": 0, "sub1": 1, "sub2": 2, "thermal": 2}
DEFAULT_THUMBNAIL_S = 2.0
# --camera sim: the simulated camera of `demo`, which shows the simulated gimbal's view.
SIMULATED_CAMERA = "sim"
SIMULATED_SCHEME = "sim:"
# A recording with video holds this much (seconds of log time) back from each flush, so a
# frame that reaches the writer after the telemetry of its moment still takes its own
# capture time as log time. Measured on the test camera: in steady state frames come up
# to 0.04 s late; the frames a camera had buffered when a stream opens up to 1.34 s.
VIDEO_HOLD_BACK_S = 2.0
_NAME = re.compile(r"^[A-Za-z0-9_-]{1,32}$")


@dataclass(frozen=True, slots=True)
class VideoSpec:
    """One stream to record: ``name`` gives the topic ``/camera/NAME``; ``url`` has the
    credentials in it (for the demuxer); ``shown`` is the URL without the password."""

    name: str
    url: str
    shown: str


def add_video_options(parser: argparse.ArgumentParser) -> None:
    """The video options of ``record`` (and any command that records)."""
    about = (
        "Record the camera's RTSP streams into the same file, time-aligned with the "
        "telemetry (copied as sent, never re-encoded). Frames reach the recorder later than "
        f"the telemetry of their moment, so with --video the last {VIDEO_HOLD_BACK_S:g} s "
        "are held back from each flush (every frame keeps its capture time as log time): "
        f"a killed recorder keeps everything older than about {VIDEO_HOLD_BACK_S + 0.5:g} s "
        "instead of about a second. Examples:"
    )
    group = parser.add_argument_group(
        "camera video",
        # the commands lay out their own text (RawDescriptionHelpFormatter): wrapped here
        textwrap.fill(about, 76) + "\n"
        "  --video main                      the main stream at 192.168.42.108:554\n"
        "  --video main --video thermal      two streams\n"
        "  --video main --camera 10.0.0.5    another camera address\n"
        "  --video front=rtsp://user:pw@10.0.0.9/live   any RTSP URL, topic /camera/front",
    )
    group.add_argument(
        "--video",
        action="append",
        default=[],
        metavar="SPEC",
        help="main, sub1, sub2, thermal (the document's streams at --camera) or NAME=rtsp://...; "
        "repeatable. Each goes to /camera/NAME (foxglove.CompressedVideo) and "
        "/camera/NAME/thumbnail (JPEG, foxglove.CompressedImage), with the tracking box, "
        "taps and angles over them on /camera/NAME/annotations and "
        "/camera/NAME/thumbnail/annotations",
    )
    group.add_argument(
        "--camera",
        default=DEFAULT_CAMERA,
        metavar="HOST[:PORT]",
        help=f"the camera of main/sub1/sub2/thermal (default {DEFAULT_CAMERA})",
    )
    group.add_argument(
        "--camera-user",
        default=None,
        metavar="USER",
        help="default admin; a user written in a NAME=rtsp://USER@... URL wins for that stream",
    )
    group.add_argument(
        "--camera-password",
        default=None,
        metavar="PASSWORD",
        help="of the streams whose URL has none (default: the first line of "
        f"--camera-password-file, else ${PASSWORD_ENV}, else admin); a password written in "
        "a NAME=rtsp://USER:PASSWORD@... URL wins for that stream. Given here it is seen "
        "by everyone in ps and kept in the shell's history: prefer the file or the variable",
    )
    group.add_argument(
        "--camera-password-file",
        default=None,
        metavar="FILE",
        help="read the camera password from the first line of FILE",
    )
    group.add_argument(
        "--thumbnail-interval",
        type=float,
        default=DEFAULT_THUMBNAIL_S,
        metavar="S",
        help=f"a JPEG thumbnail from a keyframe every S seconds (default {DEFAULT_THUMBNAIL_S:g}; "
        "0: none)",
    )


def video_specs(args: argparse.Namespace) -> list[VideoSpec]:
    """The streams the options ask for (UsageError with the reason when one is wrong,
    MissingExtra when there are some and the video extra is not installed)."""
    interval = getattr(args, "thumbnail_interval", DEFAULT_THUMBNAIL_S)
    if interval is not None and interval < 0:
        raise UsageError("--thumbnail-interval must be 0 (none) or a positive number of seconds")
    texts = getattr(args, "video", [])
    if args.camera == SIMULATED_CAMERA and not getattr(args, "simulated_camera", False):
        raise UsageError(
            "--camera sim: only `gimbal-analyzer demo` has the simulated camera (it shows "
            "the simulated gimbal's view); give the camera's HOST[:PORT]"
        )
    password = camera_password(args) if texts else None
    specs = [
        parse_video_spec(text, camera=args.camera, user=args.camera_user, password=password)
        for text in texts
    ]
    names = [spec.name for spec in specs]
    for name in names:
        if names.count(name) > 1:
            raise UsageError(f"--video {name} is given twice (each stream needs its own name)")
    if specs:
        require(VIDEO, "--video")
    return specs


def camera_password(args: argparse.Namespace) -> str | None:
    """The password of --camera-password, else of --camera-password-file, else of
    $GIMBAL_CAMERA_PASSWORD (None: the streams' own or the document's default)."""
    given = getattr(args, "camera_password", None)
    path = getattr(args, "camera_password_file", None)
    if given is not None and path is not None:
        raise UsageError("give --camera-password or --camera-password-file, not both")
    if given is not None:
        return given
    if path is not None:
        try:
            with open(path, encoding="utf-8") as handle:
                line = handle.readline().rstrip("\r\n")
        except (OSError, UnicodeDecodeError) as exc:
            why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            raise UsageError(f"--camera-password-file {path}: cannot read it ({why})") from None
        if not line:
            raise UsageError(f"--camera-password-file {path}: its first line is empty")
        return line
    return os.environ.get(PASSWORD_ENV) or None


def parse_video_spec(
    text: str,
    *,
    camera: str = DEFAULT_CAMERA,
    user: str | None = None,
    password: str | None = None,
) -> VideoSpec:
    """``main`` / ``sub1`` / ``sub2`` / ``thermal`` at ``camera``, or ``NAME=rtsp://...``."""
    if "=" in text.split("://", 1)[0]:
        name, url = text.split("=", 1)
        if not _NAME.match(name):
            raise UsageError(f"--video {text}: the name must be letters, digits, - or _")
        parts = urlsplit(url)
        if parts.scheme not in ("rtsp", "rtsps") or not parts.hostname:
            raise UsageError(
                f"--video {text}: expected NAME=rtsp://[USER:PASSWORD@]HOST[:PORT]/PATH"
            )
        return _spec(name, url, user, password)
    subtype = STREAMS.get(text)
    if subtype is None:
        raise UsageError(
            f"--video {text}: expected main, sub1, sub2, thermal or NAME=rtsp://... (see --help)"
        )
    if camera == SIMULATED_CAMERA:
        return VideoSpec(text, SIMULATED_SCHEME + text, f"the simulated camera's {text} stream")
    host, port = _camera_address(camera)
    url = f"rtsp://{host}:{port}{DOCUMENT_PATH.format(subtype=subtype)}"
    return _spec(text, url, user or DEFAULT_USER, password or DEFAULT_PASSWORD)


def is_simulated(spec: VideoSpec) -> bool:
    """A stream of the simulated camera (``--camera sim``), not an RTSP camera's."""
    return spec.url.startswith(SIMULATED_SCHEME)


def _camera_address(camera: str) -> tuple[str, int]:
    host, sep, port = camera.rpartition(":")
    if not sep or "]" in port:  # no port, or a bare IPv6 address
        host, port = camera, str(DEFAULT_RTSP_PORT)
    host = host.strip("[]")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise UsageError(f"--camera {camera}: expected HOST or HOST:PORT")
    return (f"[{host}]" if ":" in host else host), int(port)


def _spec(name: str, url: str, user: str | None, password: str | None) -> VideoSpec:
    """The stream with its credentials: those written in the URL win (another camera
    than the document's has its own), the options' fill in what the URL leaves out."""
    parts = urlsplit(url)
    if parts.username:
        user = unquote(parts.username)
    if parts.password is not None:
        password = unquote(parts.password)
    host = parts.hostname or ""
    host = f"[{host}]" if ":" in host else host
    where = f"{host}:{parts.port}" if parts.port else host
    auth = ""
    if user:
        auth = quote(user, safe="") + (":" + quote(password, safe="") if password else "") + "@"
    full = urlunsplit((parts.scheme, auth + where, parts.path, parts.query, ""))
    named = quote(user, safe="") + "@" if user else ""
    shown = urlunsplit((parts.scheme, named + where, parts.path, parts.query, ""))
    return VideoSpec(name, full, shown)


CAMERA_SOURCE_PREFIX = "camera/"  # the source of a camera stream's events: camera/NAME


def is_camera_event(event: Event) -> bool:
    """A diagnostic of a camera stream (not of the telemetry link)."""
    return event.source.startswith(CAMERA_SOURCE_PREFIX)
