"""Camera findings: what the picture showed against what the command asked for.

The optical zoom ratio is not in the feedback, so what is known of it is kept as a range
(``ZoomRange``): 1x to the gimbal type's longest at first, narrowed by every change of
scale measured and pinned by an absolute zoom that was obeyed. A relative command is
judged on its own; an absolute one (zoom_1x, specified_angle zoom) against that range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from analyzer.analysis.camera.commands import ABSOLUTE, DIRECTION, LAYOUT, PALETTE, RATIO, Asked
from analyzer.analysis.findings import NOT_OBEYED, OBEYED, PARTIAL, UNKNOWN, ResponseFinding
from analyzer.protocol.response_fields import CHECK_PICTURE

STILL = 1.03  # the picture kept its scale within 3 % (the measurement's noise is below 1 %)
TOLERANCE = 0.10  # a zoom ratio reached within 10 %
TAP_CENTRE = 0.15  # the lens pointing this near a tapped point (of the half picture): there


@dataclass
class Seen:
    """What the video showed for one command: the stream and the two frames compared, the
    change of scale (with the aircraft's motion taken out, and as the picture shows it),
    where a tapped point ended (distance from the centre, of the half picture), whether
    the palette or the layout changed, and ``problem`` when nothing could be measured."""

    stream: str
    before: float | None = None
    after: float | None = None
    scale: float | None = None
    raw_scale: float | None = None
    tap_offset: float | None = None
    changed: bool | None = None
    problem: str = ""
    uncertainty: float = 0.0  # log of the scale: how far the motion taken out may be off


@dataclass(frozen=True, slots=True)
class ZoomRange:
    """What is known of the optical zoom ratio: it lies between ``low`` and ``high``
    (1x to the ``longest`` at first). A value: what a command teaches is a new range."""

    longest: float
    low: float = 1.0
    high: float = math.inf

    def __post_init__(self) -> None:
        if self.high > self.longest:
            object.__setattr__(self, "high", self.longest)

    @property
    def pinned(self) -> bool:
        return self.high <= self.low * (1 + TOLERANCE) ** 2

    def words(self) -> str:
        if self.pinned:
            return f"{math.sqrt(self.low * self.high):.1f}x"
        return f"between {self.low:.1f}x and {self.high:.1f}x"

    def moved(self, scale: float) -> ZoomRange:
        """The range after the picture changed scale by ``scale``."""
        low = max(1.0, self.low * scale / STILL)
        high = min(self.longest, self.high * scale * STILL)
        if low > high:  # not what this range allowed: start again
            return self.forgotten()
        return ZoomRange(self.longest, low, high)

    def reached(self, ratio: float) -> ZoomRange:
        """The range once the lens was seen at ``ratio``."""
        low = max(1.0, min(ratio / (1 + TOLERANCE), self.longest))
        high = min(self.longest, max(ratio * (1 + TOLERANCE), 1.0))
        return ZoomRange(self.longest, low, high)

    def forgotten(self) -> ZoomRange:
        """Nothing known any more (the zoom may have changed unseen)."""
        return ZoomRange(self.longest)


@dataclass(frozen=True, slots=True)
class CameraVerdict:
    """The finding of one camera command and what is known of the optical zoom after it
    (None when no range was given)."""

    finding: ResponseFinding
    zoom: ZoomRange | None


def _kept(scale: float, doubt: float) -> bool:
    return abs(math.log(scale)) <= math.log(STILL) + doubt


def _unsure(scale: float, doubt: float) -> str:
    """Why a change of scale cannot be told apart from none ('' when it can)."""
    if not _kept(scale, doubt) or doubt <= math.log(STILL):
        return ""
    return (
        f"cannot tell whether the picture changed scale (x{scale:.3g}): the gimbal turned "
        "faster than the twice-a-second attitude feedback shows, so what the aircraft's "
        f"motion did to the picture is known to {(math.exp(doubt) - 1) * 100:.0f} % only"
    )


def _kept_words(scale: float, doubt: float) -> str:
    """'the picture kept its scale (x1.01)', saying so when only the motion's doubt lets
    the change pass for none."""
    if abs(math.log(scale)) <= math.log(STILL):
        return f"the picture kept its scale (x{scale:.3g})"
    return (
        f"the picture kept its scale as far as can be told (x{scale:.3g}: the aircraft's "
        f"motion leaves {(math.exp(doubt) - 1) * 100:.0f} % unsure)"
    )


def _way(scale: float) -> str:
    return "zoomed in" if scale > 1 else "zoomed out"


def judge(
    command: str, t: float, asked: Asked, seen: Seen, zoom: ZoomRange | None, already: bool
) -> CameraVerdict:
    """The finding of one camera command, and the optical zoom's range after it. ``zoom``
    is the range before (for an optical zoom command; it is not changed); ``already``: the
    palette asked is the one the camera was last seen to take (so the colours need not
    change)."""
    extra: dict[str, Any] = {
        "stream": seen.stream,
        "frame_before": seen.before,
        "frame_after": seen.after,
        "observed_at": seen.after,
    }
    forgotten = None if zoom is None else zoom.forgotten()  # it may have changed unseen
    if seen.problem:
        return CameraVerdict(
            ResponseFinding(command, t, CHECK_PICTURE, UNKNOWN, seen.problem, extra), forgotten
        )
    if asked.kind in (PALETTE, LAYOUT):
        return CameraVerdict(_changes(command, t, asked, seen, already, extra), zoom)
    assert seen.scale is not None
    scale = seen.scale
    extra["scale"] = scale
    if seen.raw_scale is not None and abs(seen.raw_scale / scale - 1) > 0.005:
        extra["raw_scale"] = seen.raw_scale
    doubt = seen.uncertainty
    unsure = _unsure(scale, doubt)
    if unsure:
        return CameraVerdict(
            ResponseFinding(command, t, CHECK_PICTURE, UNKNOWN, unsure, extra), forgotten
        )
    if asked.kind == DIRECTION:
        verdict, detail = _direction(asked, scale, zoom, doubt)
    elif asked.kind == RATIO:
        verdict, detail = _ratio(asked, scale, seen.tap_offset, extra, doubt)
    else:
        verdict, detail, after = _absolute(asked, scale, zoom, extra, doubt)
    if asked.kind == ABSOLUTE:
        zoom = None if zoom is None else after
    elif zoom is not None:
        zoom = zoom.moved(scale)
    raw = extra.get("raw_scale")
    if raw is not None:
        detail += (
            f" (x{raw:.3g} as the picture shows it: the aircraft's motion explains "
            f"x{raw / scale:.3g})"
        )
    return CameraVerdict(ResponseFinding(command, t, CHECK_PICTURE, verdict, detail, extra), zoom)


def _direction(asked: Asked, scale: float, zoom: ZoomRange | None, doubt: float) -> tuple[str, str]:
    inward = asked.value > 0
    if _kept(scale, doubt):
        end = None
        if zoom is not None and inward and zoom.low >= zoom.longest / STILL:
            end = f"its longest, {zoom.longest:g}x"
        elif zoom is not None and not inward and zoom.high <= STILL:
            end = "1x"
        if end is not None:
            return UNKNOWN, f"{_kept_words(scale, doubt)}: the lens was at {end}"
        return NOT_OBEYED, f"{_kept_words(scale, doubt)}: it did not {asked.words()}"
    if (scale > 1) == inward:
        return OBEYED, f"the picture {_way(scale)} x{scale:.3g}"
    return NOT_OBEYED, f"the picture {_way(scale)} (x{scale:.3g}) instead"


def _ratio(
    asked: Asked, scale: float, tap_offset: float | None, extra: dict[str, Any], doubt: float
) -> tuple[str, str]:
    expected = asked.value
    extra["expected_scale"] = expected
    if tap_offset is not None:
        extra["centre_offset"] = tap_offset
    if _kept(scale, doubt):
        return NOT_OBEYED, f"{_kept_words(scale, doubt)}, x{expected:g} asked"
    if (scale > 1) != (expected > 1):
        return NOT_OBEYED, f"the picture {_way(scale)} (x{scale:.3g}), x{expected:g} asked"
    words = f"the picture {_way(scale)} x{scale:.3g} of the x{expected:g} asked"
    within = abs(math.log(scale / expected)) <= math.log(1 + TOLERANCE) + doubt
    if tap_offset is not None:
        if tap_offset > TAP_CENTRE:
            words += (
                f"; the lens turned no nearer the tapped point than {tap_offset * 100:.0f} % "
                "of the way to the edge"
            )
        else:
            words += "; the lens turned to the tapped point"
        within = within and tap_offset <= TAP_CENTRE
    return (OBEYED if within else PARTIAL), words


def _absolute(
    asked: Asked, scale: float, zoom: ZoomRange | None, extra: dict[str, Any], doubt: float
) -> tuple[str, str, ZoomRange]:
    """An absolute zoom's verdict, its words and the zoom's range after it."""
    ratio = asked.value
    zoom = zoom or ZoomRange(max(ratio, 35.0))
    before = zoom.words()
    low, high = zoom.low, zoom.high
    if zoom.pinned:
        extra["expected_scale"] = ratio / math.sqrt(low * high)
    may_stay = low / (1 + TOLERANCE) <= ratio <= high * (1 + TOLERANCE)
    if _kept(scale, doubt):
        if may_stay and zoom.pinned:
            words = f"{_kept_words(scale, doubt)}: the lens was at {before}"
            return OBEYED, words, zoom.reached(ratio)
        if may_stay:
            return (
                UNKNOWN,
                f"{_kept_words(scale, doubt)}: the lens was at {ratio:g}x already, or "
                f"ignored the command (the zoom before lay {before})",
                zoom,
            )
        return NOT_OBEYED, f"{_kept_words(scale, doubt)} at {before}, {ratio:g}x asked", zoom
    inward = ratio > high * (1 + TOLERANCE)
    outward = ratio < low / (1 + TOLERANCE)
    if (inward and scale < 1) or (outward and scale > 1):
        return (
            NOT_OBEYED,
            f"the picture {_way(scale)} (x{scale:.3g}) from {before}, {ratio:g}x asked",
            zoom,
        )
    slack = STILL * math.exp(doubt)
    after_low, after_high = max(1.0, low * scale / slack), high * scale * slack
    if after_low / (1 + TOLERANCE) <= ratio <= after_high * (1 + TOLERANCE):
        if zoom.pinned:
            words = f"the picture {_way(scale)} x{scale:.3g}, from {before} to {ratio:g}x"
            return OBEYED, words, zoom.reached(ratio)
        words = (
            f"the picture {_way(scale)} x{scale:.3g}, as to {ratio:g}x (the zoom before is "
            f"known only to lie {before})"
        )
        return OBEYED, words, zoom.reached(ratio)
    moved = zoom.moved(scale)
    return (
        PARTIAL,
        f"the picture {_way(scale)} x{scale:.3g} from {before}: to {moved.words()}, not {ratio:g}x",
        moved,
    )


def _changes(
    command: str, t: float, asked: Asked, seen: Seen, already: bool, extra: dict[str, Any]
) -> ResponseFinding:
    field = "palette_changed" if asked.kind == PALETTE else "layout_changed"
    what = "its colours (the palette)" if asked.kind == PALETTE else "its layout"
    extra[field] = seen.changed
    if seen.changed is None:
        return ResponseFinding(command, t, CHECK_PICTURE, UNKNOWN, f"cannot tell {what}", extra)
    if seen.changed:
        return ResponseFinding(
            command, t, CHECK_PICTURE, OBEYED, f"the picture changed {what}", extra
        )
    if already:
        detail = f"the picture kept {what}: {asked.palette} was on already"
        return ResponseFinding(command, t, CHECK_PICTURE, OBEYED, detail, extra)
    return ResponseFinding(command, t, CHECK_PICTURE, NOT_OBEYED, f"the picture kept {what}", extra)
