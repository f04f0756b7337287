"""What the telemetry explains of the picture: the ground coming nearer as the aircraft moves.

A zoom is a change of focal length; the picture also grows when the aircraft comes nearer
to what the camera looks at (a descent, or flying toward it) and shrinks when it goes away,
and the ground is seen at another slant from elsewhere. For two frames the telemetry gives
the lens's position (GPS, altitude) and attitude (pitch, yaw from north), sampled where it
was and interpolated; flat ground seen from the two poses through one same lens says how
much the picture would have changed with no zoom at all, measured just as the picture's
change is (between the two centres): that much of it is the aircraft's, not the lens's.
A pure turn of the gimbal changes nothing here (the measure is the same however the lens
turned).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

from analyzer.protocol.types import (
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_GPS,
    Event,
)
from analyzer.scene.geometry import east_north

MIN_DOWN_DEG = 1.0  # a line of sight less steep than this meets the ground too far away
MAX_RANGE_M = 20_000.0
MAX_AGE_S = 3.0  # a sample further than this from the moment asked for is not used
# Note 1's gimbal types whose optical zoom ends at 3.5x; the others at 35x at most.
SHORT_ZOOM_TYPES = frozenset({3, 4})
SHORT_ZOOM, LONG_ZOOM = 3.5, 35.0


@dataclass
class _Series:
    """Samples of one quantity in time order (values are tuples), forgotten when old."""

    times: list[float] = field(default_factory=list)
    values: list[tuple[float, ...]] = field(default_factory=list)

    def add(self, t: float, value: tuple[float, ...]) -> None:
        if self.times and t < self.times[-1]:
            index = bisect.bisect_right(self.times, t)
            self.times.insert(index, t)
            self.values.insert(index, value)
        else:
            self.times.append(t)
            self.values.append(value)

    def at(self, t: float, angles: tuple[bool, ...] = ()) -> tuple[float, ...] | None:
        """The value at ``t``, interpolated between the samples around it (angles the short
        way round), or carried on from the last two when ``t`` is after them; None when no
        sample is within MAX_AGE_S."""
        times = self.times
        index = bisect.bisect_left(times, t)
        if 0 < index < len(times):
            a, b = index - 1, index
        elif index == len(times) and index >= 2:
            a, b = index - 2, index - 1  # past the last sample: carried on
        else:
            near = min(index, len(times) - 1)
            if not times or abs(times[near] - t) > MAX_AGE_S:
                return None
            return self.values[near]
        span = times[b] - times[a]
        if span <= 0 or span > 2 * MAX_AGE_S or t - times[b] > MAX_AGE_S:
            return None
        f = (t - times[a]) / span
        first, second = self.values[a], self.values[b]
        return tuple(
            x + f * ((y - x + 180.0) % 360.0 - 180.0 if i < len(angles) and angles[i] else y - x)
            for i, (x, y) in enumerate(zip(first, second, strict=True))
        )

    def spread(self, t: float) -> tuple[float, ...]:
        """Half of how much each value changed between the samples around ``t`` (angles
        the short way round): how far off an interpolated value may be."""
        index = bisect.bisect_left(self.times, t)
        if not 0 < index < len(self.times):
            return tuple(0.0 for _ in (self.values[0] if self.values else ()))
        a, b = self.values[index - 1], self.values[index]
        return tuple(abs((y - x + 180.0) % 360.0 - 180.0) / 2 for x, y in zip(a, b, strict=True))

    def forget_before(self, t: float) -> None:
        index = bisect.bisect_left(self.times, t - MAX_AGE_S) - 1
        if index > 0:
            del self.times[:index]
            del self.values[:index]


class Telemetry:
    """The aircraft's position and the gimbal's attitude over time, from decoded events."""

    def __init__(self) -> None:
        self.origin: tuple[float, float] | None = None  # the first GPS fix
        self.gps = _Series()
        self.altitude = _Series()
        self.attitude = _Series()  # (yaw from north, pitch)
        self.max_zoom = LONG_ZOOM

    def add(self, event: Event) -> None:
        fields, t = event.fields, event.time
        if event.topic == TOPIC_UAV_GPS:
            lat, lon = _number(fields, "latitude_deg"), _number(fields, "longitude_deg")
            if lat is None or lon is None or (lat == 0 and lon == 0):
                return
            if self.origin is None:
                self.origin = (lat, lon)
            self.gps.add(t, east_north(*self.origin, lat, lon))
        elif event.topic == TOPIC_UAV_ALTITUDE:
            altitude = _number(fields, "altitude_m")
            if altitude is not None:
                self.altitude.add(t, (altitude,))
        elif event.topic == TOPIC_GIMBAL_ATTITUDE:
            yaw, pitch = _number(fields, "yaw_deg"), _number(fields, "pitch_deg")
            if yaw is not None and pitch is not None:
                self.attitude.add(t, (yaw, pitch))
            kind = fields.get("gimbal_type_code")
            if isinstance(kind, int):
                self.max_zoom = SHORT_ZOOM if kind in SHORT_ZOOM_TYPES else LONG_ZOOM

    def forget_before(self, t: float) -> None:
        for series in (self.gps, self.altitude, self.attitude):
            series.forget_before(t)

    @property
    def knows_motion(self) -> bool:
        """Whether the recording tells where the aircraft is (altitude at least)."""
        return bool(self.altitude.times)

    def explained(self, first: float, second: float) -> float:
        """How much larger the picture's centre looks at ``second`` than at ``first``
        because the aircraft moved (1.0 when the telemetry cannot tell): the change of
        scale the picture would show with the lens unchanged, measured as the picture's is
        (between the two centres), on flat ground seen from the two positions with the
        gimbal's attitude at each."""
        return self.explained_and_doubt(first, second)[0]

    def explained_and_doubt(self, first: float, second: float) -> tuple[float, float]:
        """``explained`` and how far (log of the scale) it may be off because the attitude
        is sampled only twice a second: a gimbal that turned between two samples may have
        pointed anywhere between them at a moment in between, so the change is worked out
        again with each end's attitude moved by half the turn around it, either way."""
        one, two = self._pose(first), self._pose(second)
        if one is None or two is None:
            return 1.0, 0.0
        factor = _motion_scale(one, two)
        if factor is None:
            return 1.0, 0.0
        doubt = 0.0
        spread = (self.attitude.spread(first), self.attitude.spread(second))
        for sign in (-1.0, 1.0):
            for end in (0, 1):
                yaw, pitch = spread[end]
                if not yaw and not pitch:
                    continue
                moved = [one, two]
                pose = moved[end]
                moved[end] = _Pose(
                    pose.where, pose.yaw_deg + sign * yaw, pose.pitch_deg + sign * pitch
                )
                other = _motion_scale(moved[0], moved[1])
                if other is not None:
                    doubt = max(doubt, abs(math.log(other / factor)))
        return factor, doubt

    def _pose(self, t: float) -> _Pose | None:
        where = self._position(t)
        look = self.attitude.at(t, (True, False))
        if where is None or look is None or where[2] <= 0:
            return None
        return _Pose(where, look[0], look[1])

    def _position(self, t: float) -> tuple[float, float, float] | None:
        """East, north, up of the aircraft; without GPS, straight above where it began (only
        a climb or descent is then taken out)."""
        altitude = self.altitude.at(t)
        if altitude is None:
            return None
        where = self.gps.at(t) if self.gps.times else (0.0, 0.0)
        if where is None:
            return None
        return where[0], where[1], altitude[0]


def _motion_scale(one: _Pose, two: _Pose) -> float | None:
    """The change of scale flat ground shows between two poses of one same lens."""
    centre = (0.0, 0.0)
    at_first = _local_scale(one, two, centre)
    back = _project(one, _ground(two, centre))  # the first picture's point seen centred
    at_second = _local_scale(one, two, back) if back is not None else None
    if at_first is None or at_second is None:
        return None
    return math.sqrt(at_first * at_second)


@dataclass(frozen=True)
class _Pose:
    """The lens: where (east, north, up) and where it looks (yaw from north, pitch)."""

    where: tuple[float, float, float]
    yaw_deg: float
    pitch_deg: float

    def axes(self) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
        """Forward, right and down unit vectors (east, north, up), no roll."""
        yaw, pitch = math.radians(self.yaw_deg), math.radians(self.pitch_deg)
        forward = (
            math.cos(pitch) * math.sin(yaw),
            math.cos(pitch) * math.cos(yaw),
            math.sin(pitch),
        )
        right = (math.cos(yaw), -math.sin(yaw), 0.0)
        down = (
            math.sin(pitch) * math.sin(yaw),
            math.sin(pitch) * math.cos(yaw),
            -math.cos(pitch),
        )
        return forward, right, down


def _ground(pose: _Pose, pixel: tuple[float, float] | None) -> tuple[float, ...] | None:
    """Where the ray through a pixel (normalised: x right, y down, 1 = one focal length
    from the centre) meets flat ground; None for the horizon and the sky."""
    if pixel is None:
        return None
    forward, right, down = pose.axes()
    ray = [f + pixel[0] * r + pixel[1] * d for f, r, d in zip(forward, right, down, strict=True)]
    norm = math.sqrt(sum(v * v for v in ray))
    if -ray[2] / norm < math.sin(math.radians(MIN_DOWN_DEG)):
        return None
    t = pose.where[2] / -ray[2]
    point = tuple(w + t * v for w, v in zip(pose.where, ray, strict=True))
    if math.dist(point, pose.where) > MAX_RANGE_M:
        return None
    return point


def _project(pose: _Pose, point: tuple[float, ...] | None) -> tuple[float, float] | None:
    """The normalised pixel where a ground point appears (None: behind the lens)."""
    if point is None:
        return None
    forward, right, down = pose.axes()
    offset = [p - w for p, w in zip(point, pose.where, strict=True)]
    depth = sum(o * f for o, f in zip(offset, forward, strict=True))
    if depth <= 0:
        return None
    x = sum(o * r for o, r in zip(offset, right, strict=True)) / depth
    y = sum(o * d for o, d in zip(offset, down, strict=True)) / depth
    return x, y


def _local_scale(one: _Pose, two: _Pose, pixel: tuple[float, float]) -> float | None:
    """How much the ground seen at ``pixel`` of the first picture is magnified in the
    second (the square root of the Jacobian's determinant, by finite differences)."""
    step = 1e-3
    points = []
    for dx, dy in ((0.0, 0.0), (step, 0.0), (0.0, step)):
        seen = _project(two, _ground(one, (pixel[0] + dx, pixel[1] + dy)))
        if seen is None:
            return None
        points.append(seen)
    (x0, y0), (x1, y1), (x2, y2) = points
    determinant = ((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)) / step**2
    return math.sqrt(determinant) if determinant > 0 else None


def _number(fields: dict[str, object], name: str) -> float | None:
    value = fields.get(name)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)
