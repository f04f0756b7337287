"""The one rule for times in human output: UTC with a ``Z``, or local time with its offset."""

from __future__ import annotations

import time as _time

# Times below this are relative (seconds since the start of a log), not Unix times.
EPOCH_THRESHOLD = 946_684_800.0  # 2000-01-01T00:00:00Z

_local = False


def use_local_time(local: bool) -> None:
    """Switch every human time of this process to local time (True) or UTC (False)."""
    global _local
    _local = bool(local)


def local_time() -> bool:
    """True when times are shown in local time."""
    return _local


def is_absolute(t: float) -> bool:
    """True for Unix times, False for relative log times."""
    return t >= EPOCH_THRESHOLD


def _split(t: float) -> tuple[int, int]:
    whole = int(t)
    millis = round((t - whole) * 1000)
    if millis >= 1000:
        whole, millis = whole + 1, 0
    return whole, millis


def _zone(whole: int) -> tuple[_time.struct_time, str]:
    if not _local:
        return _time.gmtime(whole), "Z"
    parts = _time.localtime(whole)
    offset = parts.tm_gmtoff or 0
    sign = "-" if offset < 0 else "+"
    offset = abs(offset) // 60
    return parts, f"{sign}{offset // 60:02d}:{offset % 60:02d}"


def format_datetime(t: float) -> str:
    """``2024-05-14 10:00:01.253Z`` (or ``... 12:00:01.253+02:00``); relative times as seconds."""
    if not is_absolute(t):
        return f"{t:.3f} s"
    whole, millis = _split(t)
    parts, zone = _zone(whole)
    return _time.strftime("%Y-%m-%d %H:%M:%S", parts) + f".{millis:03d}{zone}"


def format_clock(t: float) -> str:
    """``10:00:01.253Z`` (or ``12:00:01.253+02:00``); relative times as ``12.345``."""
    if not is_absolute(t):
        return f"{t:.3f}"
    whole, millis = _split(t)
    parts, zone = _zone(whole)
    return _time.strftime("%H:%M:%S", parts) + f".{millis:03d}{zone}"


def clock_width() -> int:
    """Characters of a ``format_clock`` time (for aligned columns)."""
    return 18 if _local else 13


FLAG_HELP = "show times in local time with its UTC offset instead of UTC (Z)"
