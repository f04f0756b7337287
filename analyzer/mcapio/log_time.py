"""MCAP log times: event seconds as the file's unsigned nanoseconds."""

from __future__ import annotations

MAX_LOG_SECONDS = (2**64 - 1) / 1e9


def time_ns(seconds: float) -> int:
    """Event time in seconds -> MCAP log time in nanoseconds (clamped to the uint64 range)."""
    if 0 < seconds < MAX_LOG_SECONDS:  # False for NaN too
        return round(seconds * 1e9)
    return 2**64 - 1 if seconds >= MAX_LOG_SECONDS else 0


def timestamp(seconds: float) -> dict[str, int]:
    """Seconds -> foxglove time {sec, nsec}, equal to the message's log time."""
    sec, nsec = divmod(time_ns(seconds), 1_000_000_000)
    return {"sec": sec, "nsec": nsec}
