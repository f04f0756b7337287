"""The picture followed across a run of frames: its change of scale from the first to the last.

Two frames far apart may share too little to be matched (a zoom of 30x, a gimbal that
turned a whole field of view), so the run is bridged by the fewest frames in between that
can be: from each frame reached, the furthest frame that still matches is taken next
(trying the last first, then halving the step). Scales multiply along the way, and so do
the homographies, which say where a point of the first frame ends up in the last.

Each link's scale is also divided by what the aircraft's motion explains over it
(``explained``: how much nearer the ground at the picture's centre came), so that a
climbing or approaching aircraft is not taken for a zoom, and what that may be off by
is summed.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from analyzer.analysis.camera.motion import MIN_FEATURES, Features, features, motion


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
    the one at hand)."""
    cache = cache or FeatureCache(pictures)
    last = len(pictures) - 1
    total = np.eye(3)
    scale = raw = 1.0
    links = 0
    weakest = 0
    anchor = 0
    path: list[tuple[int, np.ndarray]] = [(0, total)]
    scales = [1.0]
    doubt = 0.0
    if last < 1:
        return Followed(total, scale, raw, 0, 0, 0, "" if last == 0 else LOST)
    if cache[0].count < MIN_FEATURES:
        return Followed(total, scale, raw, 0, 0, 0, TOO_LITTLE_TEXTURE)
    while anchor < last:
        step = last - anchor
        if times is not None:
            while step > 1 and times[anchor + step] - times[anchor] > MAX_LINK_S:
                step //= 2
        found = None
        while step >= 1:
            found = motion(cache[anchor], cache[anchor + step])
            if found is not None:
                break
            step //= 2
        if found is None:
            problem = TOO_LITTLE_TEXTURE if cache[anchor + 1].count < MIN_FEATURES else LOST
            return Followed(
                total,
                scale,
                raw,
                links,
                weakest,
                anchor,
                problem,
                tuple(path),
                tuple(scales),
                doubt,
            )
        total = found.homography @ total
        total /= total[2, 2] if total[2, 2] else 1.0
        raw *= found.scale
        motion_part, unsure = explained(anchor, anchor + step) if explained else (1.0, 0.0)
        scale *= found.scale / motion_part
        doubt += unsure
        weakest = found.inliers if not links else min(weakest, found.inliers)
        links += 1
        anchor += step
        path.append((anchor, total))
        scales.append(scale)
    return Followed(total, scale, raw, links, weakest, last, "", tuple(path), tuple(scales), doubt)
