"""The one rule for times in human output: UTC with a ``Z``, or local time with its offset."""

from __future__ import annotations

import time as _time
from dataclasses import dataclass
from typing import Final

# Times below this are relative (seconds since the start of a log), not Unix times.
EPOCH_THRESHOLD: Final = 946_684_800.0  # 2000-01-01T00:00:00Z

FLAG_HELP: Final = "show times in local time with its UTC offset instead of UTC (Z)"


def is_absolute(t: float) -> bool:
    """True for Unix times, False for relative log times."""
    return t >= EPOCH_THRESHOLD


def _split(t: float) -> tuple[int, int]:
    whole = int(t)
    millis = round((t - whole) * 1000)
    if millis >= 1000:
        whole, millis = whole + 1, 0
    return whole, millis


@dataclass(frozen=True)
class TimeZone:
    """How one output shows Unix times: in UTC with ``Z`` (:data:`UTC`, the default
    everywhere) or in local time with its UTC offset (:data:`LOCAL`, ``--local-time``).

    The command line makes one from ``--local-time`` and hands it to what renders times
    for people. Texts that become data (a diagnostic's detail, a check's verdict, JSON)
    are written in :data:`UTC`, whatever the display shows."""

    local: bool = False

    def _parts(self, whole: int) -> tuple[_time.struct_time, str]:
        if not self.local:
            return _time.gmtime(whole), "Z"
        parts = _time.localtime(whole)
        offset = parts.tm_gmtoff or 0
        sign = "-" if offset < 0 else "+"
        offset = abs(offset) // 60
        return parts, f"{sign}{offset // 60:02d}:{offset % 60:02d}"

    def format_datetime(self, t: float) -> str:
        """``2024-05-14 10:00:01.253Z`` (or ``... 12:00:01.253+02:00``); relative times
        as seconds."""
        if not is_absolute(t):
            return f"{t:.3f} s"
        whole, millis = _split(t)
        parts, zone = self._parts(whole)
        return _time.strftime("%Y-%m-%d %H:%M:%S", parts) + f".{millis:03d}{zone}"

    def format_clock(self, t: float) -> str:
        """``10:00:01.253Z`` (or ``12:00:01.253+02:00``); relative times as ``12.345``."""
        if not is_absolute(t):
            return f"{t:.3f}"
        whole, millis = _split(t)
        parts, zone = self._parts(whole)
        return _time.strftime("%H:%M:%S", parts) + f".{millis:03d}{zone}"

    @property
    def clock_width(self) -> int:
        """Characters of a ``format_clock`` time (for aligned columns)."""
        return 18 if self.local else 13


UTC: Final = TimeZone()
LOCAL: Final = TimeZone(local=True)


def chosen_zone(local_time: bool) -> TimeZone:
    """The zone of ``--local-time`` (given or not)."""
    return LOCAL if local_time else UTC
