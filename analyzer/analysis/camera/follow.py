"""The picture followed across a run of frames: its change of scale from the first to the last.

Two frames far apart may share too little to be matched (a zoom of 30x, a gimbal that
turned a whole field of view), so the run is bridged by the fewest frames in between that
can be: from each frame reached, the furthest frame that still matches is taken next
(trying the last first, then halving the step). Scales multiply along the way, and so do
the homographies, which say where a point of the first frame ends up in the last.

Each link's scale is also divided by what the aircraft's motion explains over it
(``explained``: how much nearer the ground at the picture's centre came), so that a
climbing or approaching aircraft is not taken for a zoom, and what that may be off by
is summed. A link that only a few matches agree on is believed only when the links
around it vouch for it (``weak_links``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from analyzer.analysis.camera.motion import MIN_FEATURES, Features, Motion, features, motion
from analyzer.analysis.camera.weak_links import (
    WEAK_INLIERS,
    PictureLink,
    first_doubted,
    neighbours,
)


@dataclass(frozen=True)
class Followed:
    """The picture followed from frame 0 to frame ``reached``: the homography from the
    first to that frame, the change of scale with what the aircraft's motion explains
    taken out (``scale``) and as the picture shows it (``raw_scale``), how many links it
    took and the fewest inliers one of them had; ``problem`` says why it stopped short
    (empty when it reached the last frame)."""

    homography: np.ndarray
    scale: float
    raw_scale: float
    links: int
    inliers: int
    reached: int
    problem: str = ""
    # the frames the links went through, with the homography from the first one to each
    path: tuple[tuple[int, np.ndarray], ...] = ()
    scales: tuple[float, ...] = ()  # ``scale`` from the first frame to each of ``path``
    # how far (log of the scale) what the telemetry explains may be off, summed over the
    # links (its attitude is sampled twice a second while the gimbal may turn 60 deg/s)
    uncertainty: float = 0.0
    # with a WEAK_LINK problem: the link not believed, and the strong links next to it
    doubted: tuple[PictureLink, tuple[PictureLink, ...]] | None = None

    def settled(self, times: Sequence[float], seconds: float, within: float) -> bool:
        """Whether the scale stayed within ``within`` (a fraction) over the last
        ``seconds`` of the frames followed."""
        end = times[self.reached]
        for (index, _), scale in zip(reversed(self.path), reversed(self.scales), strict=True):
            if end - times[index] >= seconds:
                return abs(self.scale / scale - 1) <= within
        return False

    @property
    def complete(self) -> bool:
        return not self.problem


TOO_LITTLE_TEXTURE = "too little texture"
LOST = "lost"
WEAK_LINK = "weak link"  # a link that too few matches agree on, and its neighbours do not vouch for


class FeatureCache:
    """Each frame's features, computed once however often it is tried."""

    def __init__(self, pictures: Sequence[np.ndarray]) -> None:
        self.pictures = pictures
        self._found: dict[int, Features] = {}

    def __getitem__(self, index: int) -> Features:
        found = self._found.get(index)
        if found is None:
            found = self._found[index] = features(self.pictures[index])
        return found

    @property
    def computed(self) -> int:
        return len(self._found)


# explained(first index, second index): the change of scale the aircraft's motion causes
# between two frames (1.0 when it is not known) and how far (log) that may be off
Explained = Callable[[int, int], tuple[float, float]]


MAX_LINK_S = 1.0  # frames further apart are not matched directly: the scene moved too much


def follow(
    pictures: Sequence[np.ndarray],
    cache: FeatureCache | None = None,
    explained: Explained | None = None,
    times: Sequence[float] | None = None,
) -> Followed:
    """Follow the picture from the first of ``pictures`` to the last (taken at ``times``:
    no link spans more than MAX_LINK_S, so a repeating texture far on is not taken for
    the one at hand). A weak link (too few matches agree: ``weak_links``) is taken only
    when no strong one leaves its frame, and believed only when the links around it
    vouch for it; otherwise the picture is followed no further than its first frame."""
    cache = cache or FeatureCache(pictures)
    last = len(pictures) - 1
    clock = times if times is not None else [float(i) for i in range(len(pictures))]
    if last < 1:
        return Followed(np.eye(3), 1.0, 1.0, 0, 0, 0, "" if last == 0 else LOST)
    if cache[0].count < MIN_FEATURES:
        return Followed(np.eye(3), 1.0, 1.0, 0, 0, 0, TOO_LITTLE_TEXTURE)
    links: list[tuple[PictureLink, np.ndarray]] = []
    anchor = 0
    problem = ""
    while anchor < last:
        step = last - anchor
        if times is not None:
            while step > 1 and times[anchor + step] - times[anchor] > MAX_LINK_S:
                step //= 2
        found = _link(cache, anchor, step)
        if found is None:
            problem = TOO_LITTLE_TEXTURE if cache[anchor + 1].count < MIN_FEATURES else LOST
            break
        step, measured = found
        motion_part, unsure = explained(anchor, anchor + step) if explained else (1.0, 0.0)
        link = PictureLink(
            anchor,
            anchor + step,
            clock[anchor],
            clock[anchor + step],
            measured.inliers,
            measured.matches,
            measured.scale,
            motion_part,
            unsure,
        )
        links.append((link, measured.homography))
        anchor += step
    chain = [link for link, _ in links]
    index = first_doubted(chain)
    doubted = None
    if index is not None:
        doubted = chain[index], tuple(neighbours(chain, index))
        problem = WEAK_LINK
        del links[index:]
    return _followed(links, problem, doubted)


def _link(cache: FeatureCache, anchor: int, step: int) -> tuple[int, Motion] | None:
    """The link from frame ``anchor``: to the furthest frame of ``anchor + step``, then
    of half as far and so on, that matches; when only a weak link is found that way, the
    longest strong one to any nearer frame instead (the chain then goes through other
    frames), else that weak one."""
    found: Motion | None = None
    while step >= 1:
        found = motion(cache[anchor], cache[anchor + step])
        if found is not None:
            break
        step //= 2
    if found is None:
        return None
    if found.inliers >= WEAK_INLIERS:
        return step, found
    for nearer in range(step - 1, 0, -1):
        other = motion(cache[anchor], cache[anchor + nearer])
        if other is not None and other.inliers >= WEAK_INLIERS:
            return nearer, other
    return step, found


def _followed(
    links: list[tuple[PictureLink, np.ndarray]],
    problem: str,
    doubted: tuple[PictureLink, tuple[PictureLink, ...]] | None,
) -> Followed:
    """The Followed of a chain of links (``problem``: why it stopped where it did)."""
    total = np.eye(3)
    scale = raw = 1.0
    doubt = 0.0
    path: list[tuple[int, np.ndarray]] = [(0, total)]
    scales = [1.0]
    for link, homography in links:
        total = homography @ total
        total /= total[2, 2] if total[2, 2] else 1.0
        raw *= link.raw_scale
        scale *= link.lens
        doubt += link.doubt
        path.append((link.second, total))
        scales.append(scale)
    weakest = min((link.inliers for link, _ in links), default=0)
    reached = links[-1][0].second if links else 0
    return Followed(
        total,
        scale,
        raw,
        len(links),
        weakest,
        reached,
        problem,
        tuple(path),
        tuple(scales),
        doubt,
        doubted,
    )
