"""Weak links: a measurement between two frames that barely enough matches agree on.

In a picture with little texture (soft water, haze at long zoom) the matches that agree on
one motion of the scene may be few, and the overlays burnt into the picture (the centre
cross, text) or the codec's blocks can then win RANSAC's vote with a wrong change of
scale: a link's scale is x1.15 while the lens went x0.57. Such a link is not believed on
its own. Its change of scale, with what the aircraft's motion explains taken out (the
telemetry's account), is held against the strong links on either side of it in the
chain: it must agree with each of them (the lens may zoom faster over it than around
it, but not the other way, nor stand still while a neighbour zooms). A weak link that
no strong neighbour vouches for leaves the change of scale unknown.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from analyzer.analysis.camera.motion import MIN_INLIERS

WEAK_INLIERS = 2 * MIN_INLIERS  # fewer agreeing matches than this: a weak link
AGREE = math.log(1.05)  # a weak link agrees with its neighbours within 5 % (and the doubt)
FASTER = 2.0  # over a weak link the lens may zoom up to this much faster than around it


@dataclass(frozen=True)
class PictureLink:
    """One measurement between frames ``first`` and ``second`` (taken at ``start`` and
    ``end``): how many matches agreed of those found, the change of scale the picture
    shows (``raw_scale``), what the aircraft's motion explains of it (``explained``) and
    how far (log) that may be off (``doubt``)."""

    first: int
    second: int
    start: float
    end: float
    inliers: int
    matches: int
    raw_scale: float
    explained: float = 1.0
    doubt: float = 0.0

    @property
    def lens(self) -> float:
        """The lens's own change of scale: the picture's, the aircraft's motion taken out."""
        return self.raw_scale / self.explained

    @property
    def weak(self) -> bool:
        return self.inliers < WEAK_INLIERS

    @property
    def rate(self) -> float:
        """The lens's change of scale per second (log)."""
        return math.log(self.lens) / max(self.end - self.start, 1e-6)


def neighbours(links: Sequence[PictureLink], index: int) -> list[PictureLink]:
    """The nearest strong link before ``links[index]`` and the nearest after it."""
    before = next((n for n in reversed(links[:index]) if not n.weak), None)
    after = next((n for n in links[index + 1 :] if not n.weak), None)
    return [n for n in (before, after) if n is not None]


def vouched(link: PictureLink, around: Sequence[PictureLink]) -> bool:
    """Whether the strong links ``around`` a weak one vouch for its change of scale: each
    of them, zooming as it did (up to FASTER times as fast), would have made about as
    much of the weak link's time, give or take AGREE and the telemetry's doubt. A link
    where the lens starts or stops (one neighbour zooms, the other does not) is so not
    believed: that is where a false match on the overlays (no zoom) hides best."""
    if not around:
        return False
    span = link.end - link.start
    change = math.log(link.lens)
    for neighbour in around:
        expected = neighbour.rate * span
        slack = AGREE + link.doubt + neighbour.doubt
        low, high = sorted((expected, FASTER * expected))
        if not low - slack <= change <= high + slack:
            return False
    return True


def first_doubted(links: Sequence[PictureLink]) -> int | None:
    """The index of the first weak link that its neighbours do not vouch for (None: all
    links are believed)."""
    for index, link in enumerate(links):
        if link.weak and not vouched(link, neighbours(links, index)):
            return index
    return None


def doubt_words(link: PictureLink, around: Sequence[PictureLink], origin: float) -> str:
    """Why a weak link is not believed, in words (its times from ``origin``, the
    command's time)."""
    head = (
        f"the picture's change of scale from {_when(link.start - origin)} to "
        f"{_when(link.end - origin)} (x{link.lens:.3g}) rests on a weak link: only "
        f"{link.inliers} matches (of {link.matches}) agree on one motion"
    )
    if not around:
        return f"{head}, and no strong link next to it confirms it"
    rates = " and ".join(f"x{math.exp(n.rate * (link.end - link.start)):.3g}" for n in around)
    return f"{head}, and the strong links next to it (zooming as they did: {rates}) disagree"


def _when(offset: float) -> str:
    if abs(offset) < 0.005:
        return "the command"
    return f"{abs(offset):.2f} s {'before' if offset < 0 else 'after'} the command"
