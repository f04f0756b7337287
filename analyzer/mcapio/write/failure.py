"""After a write error: keep every chunk written completely and finish the file if there is room."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable

from analyzer.mcapio.channels import STATS_METADATA_NAME
from analyzer.mcapio.write.chunked_writer import ChunkedWriter
from analyzer.timefmt import UTC, TimeZone, is_absolute


def keep_complete_chunks(
    writer: ChunkedWriter, fd: int, stats: Callable[[], dict[str, str]]
) -> None:
    """Cut off the half-written tail of the file ``writer`` writes to (descriptor ``fd``).

    If the space it freed allows, the file is finished (the ``stats`` metadata record, the
    summary), so it opens like any other recording, with the messages a hold-back kept
    out of the failed chunk; else the summary alone is tried (what a live flush writes),
    so the file still opens indexed; else only the complete chunks stay, an unfinished
    recording the reader recovers. Write errors here are swallowed."""
    good = writer.position
    writer.drop_open_chunk()  # messages a hold-back kept out of it stay, tried by finish
    try:
        os.ftruncate(fd, good)
        os.lseek(fd, good, os.SEEK_SET)
        if writer.message_count or writer.held_messages:
            writer.add_metadata(STATS_METADATA_NAME, stats())
            writer.finish()
        os.fsync(fd)
    except OSError:
        end = writer.position
        writer.drop_open_chunk()  # the held-back messages did not fit either
        try:
            os.ftruncate(fd, end)
            os.lseek(fd, end, os.SEEK_SET)
            if writer.message_count:
                writer.finish()
        except OSError:
            with contextlib.suppress(OSError):
                os.ftruncate(fd, end)
        with contextlib.suppress(OSError):
            os.fsync(fd)


def format_clock(seconds: float | None, zone: TimeZone = UTC) -> str:
    """HH:MM:SS.mmmZ (UTC, or local time in ``zone`` local) of a Unix time; seconds for
    small (relative) times."""
    if seconds is None:
        return "-"
    if not is_absolute(seconds):  # a relative time, not a date
        return f"{seconds:.3f} s"
    return zone.format_clock(seconds)
