"""Bounded plot series of any flight length: time buckets that keep each column's extremes."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

Row = tuple[Any, ...]  # (time, value, value, ..., extra, ...)

FINE_BUCKETS = 6000  # buckets kept per series; the page re-buckets these for its view
# The gimbal's attitude (and the rates measured from it) in finer buckets: every sample of
# a 40 Hz feedback over 1,000 s still fits, so a zoom shows each one.
ATTITUDE_BUCKETS = 32768
FIRST_WIDTH_S = 0.001  # bucket width to start with; doubled whenever there are too many


def _extremes(rows: Sequence[Row], columns: Sequence[int]) -> list[Row]:
    """The rows holding the minimum and the maximum of each column, in time order, once."""
    if not columns:  # marks: the first of the bucket
        return [min(rows, key=lambda r: r[0])]
    if len(rows) <= 2:
        return sorted(rows, key=lambda r: r[0])
    kept: dict[int, Row] = {}
    for c in columns:
        low = min(rows, key=lambda r: r[c])
        high = max(rows, key=lambda r: r[c])
        kept[id(low)] = low
        kept[id(high)] = high
    return sorted(kept.values(), key=lambda r: r[0])


class Decimator:
    """Rows grouped in time buckets, keeping per bucket only the rows that hold the minimum
    and the maximum of each of ``columns``: a line through what is kept has every peak and
    every trough of the full series, and each point is a real sample.

    Memory stays bounded whatever the flight's length: when more than ``limit`` buckets
    are in use the bucket width doubles and neighbouring buckets merge. A series shorter
    than ``limit`` buckets of 1 ms (every short flight) is kept whole.
    """

    def __init__(self, columns: Sequence[int], limit: int = FINE_BUCKETS) -> None:
        self.columns = tuple(columns)
        self.limit = limit
        self.width = FIRST_WIDTH_S
        self.origin: float | None = None
        self.buckets: dict[int, list[Row]] = {}
        self.count = 0  # rows added

    def add(self, row: Row) -> None:
        t = float(row[0])
        if self.origin is None:
            self.origin = t
        self.count += 1
        key = math.floor((t - self.origin) / self.width)
        bucket = self.buckets.get(key)
        if bucket is None:
            self.buckets[key] = [row]
            if len(self.buckets) > self.limit:
                self._coarsen()
            return
        bucket.append(row)
        if len(bucket) > (2 * len(self.columns) + 1 if self.columns else 1):
            bucket[:] = _extremes(bucket, self.columns)

    def _coarsen(self) -> None:
        while len(self.buckets) > self.limit:
            self.width *= 2
            merged: dict[int, list[Row]] = {}
            for key, rows in self.buckets.items():
                merged.setdefault(key // 2, []).extend(rows)
            self.buckets = {k: _extremes(rows, self.columns) for k, rows in merged.items()}

    def rows(self) -> list[Row]:
        """What is kept, in time order."""
        out: list[Row] = []
        for key in sorted(self.buckets):
            out.extend(_extremes(self.buckets[key], self.columns))
        return out

    @property
    def whole(self) -> bool:
        """True while every row added is still kept."""
        return sum(len(rows) for rows in self.buckets.values()) == self.count


class PerSecond:
    """Events per whole second, folded as they come (times mostly in order) into a
    :class:`Decimator` of (second, count); seconds without events count 0 when ``zeros``."""

    def __init__(self, zeros: bool, limit: int = FINE_BUCKETS) -> None:
        self.zeros = zeros
        self.series = Decimator((1,), limit)
        self.open: dict[int, int] = {}
        self.flushed: int | None = None  # the last second handed to the series
        self.first: float | None = None

    def add(self, t: float) -> None:
        second = math.floor(t)
        if self.first is None or t < self.first:
            self.first = t
        if self.flushed is not None and second <= self.flushed:
            second = self.flushed + 1  # late by more than the window: counted in the next
        self.open[second] = self.open.get(second, 0) + 1
        if len(self.open) > 8:  # a few seconds may still get late events
            self._flush(min(self.open))

    def _flush(self, second: int) -> None:
        count = self.open.pop(second)
        if self.zeros and self.flushed is not None and second > self.flushed + 1:
            self.series.add((float(self.flushed + 1), 0))
            if second > self.flushed + 2:
                self.series.add((float(second - 1), 0))
        self.series.add((float(second), count))
        self.flushed = second

    def rows(self, until: float | None = None) -> list[Row]:
        """(second, count) rows; with ``zeros``, silent seconds up to ``until`` count 0."""
        while self.open:
            self._flush(min(self.open))
        if self.zeros and until is not None and self.flushed is not None:
            end = math.floor(until)
            if end > self.flushed:
                self.series.add((float(self.flushed + 1), 0))
                self.series.add((float(end), 0))
                self.flushed = end
        rows = self.series.rows()
        if rows and self.first is not None and rows[0][0] < self.first:
            rows[0] = (self.first, *rows[0][1:])  # the first second starts with the input
        return rows
