"""GPS week and milliseconds of the week -> UTC seconds since 1970, with leap seconds."""

from __future__ import annotations

import bisect
import calendar

GPS_EPOCH = 315_964_800  # 1980-01-06 00:00:00 UTC, the start of GPS week 0
WEEK = 604_800

# UTC dates from which GPS time runs one more second ahead of UTC (IERS Bulletin C;
# GPS - UTC = TAI - UTC - 19 s). The last one, 2017-01-01, makes it 18 s.
_LEAP_DATES = (
    (1981, 7),
    (1982, 7),
    (1983, 7),
    (1985, 7),
    (1988, 1),
    (1990, 1),
    (1991, 1),
    (1992, 7),
    (1993, 7),
    (1994, 7),
    (1996, 1),
    (1997, 7),
    (1999, 1),
    (2006, 1),
    (2009, 1),
    (2012, 7),
    (2015, 7),
    (2017, 1),
)
# The same instants counted in GPS seconds since 1980-01-06, each with the offset from it on.
_LEAPS_GPS = tuple(
    calendar.timegm((year, month, 1, 0, 0, 0)) - GPS_EPOCH + n
    for n, (year, month) in enumerate(_LEAP_DATES, start=1)
)


def leap_seconds(gps_seconds: float) -> int:
    """GPS - UTC in whole seconds at a time given in seconds since the GPS epoch."""
    return bisect.bisect_right(_LEAPS_GPS, gps_seconds)


def gps_to_utc(week: int, week_ms: int) -> float:
    """UTC (seconds since 1970) of a GPS week and millisecond of the week."""
    gps_seconds = week * WEEK + week_ms / 1000.0
    return GPS_EPOCH + gps_seconds - leap_seconds(gps_seconds)


def utc_to_gps(utc: float) -> tuple[int, int]:
    """The GPS week and millisecond of the week of a UTC time (the inverse of gps_to_utc)."""
    gps_seconds = utc - GPS_EPOCH
    gps_seconds += leap_seconds(gps_seconds + leap_seconds(gps_seconds))
    week, rest = divmod(gps_seconds, WEEK)
    return int(week), round(rest * 1000)
