"""How record, monitor and demo attach the live Foxglove server: start it, say where, sum up."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import IO, TYPE_CHECKING

from analyzer.errors import UsageError

if TYPE_CHECKING:
    from analyzer.live.server import FoxgloveLive
    from analyzer.mcapio.channels import ChannelSpec


def start_foxglove(
    args: argparse.Namespace, *, encode: bool = False, stream: IO[str] | None = None
) -> FoxgloveLive | None:
    """The live server ``--foxglove`` asks for (None without it), listening at once; where it
    listens is said on ``stream`` (standard error by default), all interfaces included.
    ``encode``: no recording feeds it (``McapSink(..., tee=live)``), it encodes batches."""
    listen = getattr(args, "foxglove", None)
    if listen is None:
        return None
    try:
        from analyzer.live.server import FoxgloveLive
    except ImportError as exc:
        raise UsageError(
            f"--foxglove needs the foxglove-sdk package (pip install foxglove-sdk): {exc}"
        ) from None
    live = FoxgloveLive(listen, encode=encode, channels=camera_channels(args))
    print(f"foxglove: {live.describe()}", file=stream or sys.stderr, flush=True)
    return live


def camera_channels(args: argparse.Namespace) -> list[ChannelSpec]:
    """The channels of the ``--video`` streams, advertised from the start like the others
    (a channel advertised while a client is connected may not reach it at once)."""
    if not getattr(args, "video", None):
        return []
    from analyzer.mcapio.write.video import camera_channel_specs
    from analyzer.video.spec import video_specs

    return [spec for video in video_specs(args) for spec in camera_channel_specs(video.name)]


def with_foxglove(label: str, live: FoxgloveLive | None) -> str:
    """A monitor screen's source label, with the address Foxglove connects to."""
    return label if live is None else f"{label}  |  Foxglove {live.url}"


def foxglove_note(live: FoxgloveLive | None) -> str:
    """The live server's part of a status line ('' without one)."""
    if live is None:
        return ""
    from analyzer.live.server import status_words

    return status_words(live)


def foxglove_status(live: FoxgloveLive | None) -> Callable[[], tuple[str, bool]] | None:
    """For the monitor's status bar: a call giving the live server's words and whether a
    client lost messages (None without a server)."""
    if live is None:
        return None
    from analyzer.live.server import status_words

    server = live

    def words() -> tuple[str, bool]:
        return status_words(server), server.status().drop_reports > 0

    return words


def foxglove_summary(live: FoxgloveLive | None) -> str:
    """One closing line about the live server ('' without one)."""
    if live is None:
        return ""
    status = live.status()
    text = (
        f"foxglove: served {status.messages} messages on {status.channels} channels at {live.url}"
    )
    if status.drop_reports:
        text += (
            "; a client fell behind and messages to it were dropped (the SDK reported it "
            f"{status.drop_reports} time(s); it does not count the messages)"
        )
    if status.refused:
        text += (
            f"; {status.refused} connection(s) refused: the client did not speak "
            "foxglove.sdk.v1 (Foxglove Studio 1.x speaks only foxglove.websocket.v1)"
        )
    if status.errors:
        text += f"; {status.errors} message(s) the SDK refused"
    return text
