"""Did the picture-in-picture layout change? Each frame predicted from the one before it.

From one frame to the next the scene moves by a homography (the gimbal turning, the lens
zooming, the aircraft flying over flat ground), which matched features give, and an inset
showing the other sensor moves by one of its own (and the camera's overlays stand still);
the frame before, moved by the best of these at each pixel, predicts the next one
everywhere the layout stayed. An inset that appears, goes or swaps sensors makes a block
of the picture unpredictable at once: a share of the picture far off its prediction,
beyond what compression and parallax leave.
When no motion can be matched at all between two frames that follow each other, the
whole picture changed (a visible picture replaced by the thermal one). A change is a
step: the frame before it and the one after it differ as much, whereas a motion matched
badly once leaves those two alike; so each change found is checked that way.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

from analyzer.analysis.camera.follow import FeatureCache
from analyzer.analysis.camera.motion import MIN_FEATURES, motions

OFF_LEVELS = 40  # a pixel this far (0..255 grey) from its prediction is not predicted
CHANGED_SHARE = 0.04  # this share of the picture unpredicted at once: the layout changed
MARGIN = 0.04  # the picture's edges are left out (what came into view as it moved)
MOTIONS = 3  # the scene, an inset of the other sensor, and what stands still (the overlays)


def unpredicted(before: np.ndarray, after: np.ndarray, homographies: Sequence[np.ndarray]) -> float:
    """The share of ``after`` that ``before`` moved by none of ``homographies`` predicts."""
    h, w = after.shape[:2]
    smooth_before = cv2.GaussianBlur(before, (5, 5), 0)
    smooth_after = cv2.GaussianBlur(after, (5, 5), 0)
    off = np.full((h, w), 255, np.uint8)
    seen = np.zeros((h, w), bool)
    for homography in homographies:
        moved = cv2.warpPerspective(smooth_before, homography, (w, h), flags=cv2.INTER_LINEAR)
        inside = cv2.warpPerspective(np.full((h, w), 255, np.uint8), homography, (w, h)) == 255
        difference = cv2.absdiff(moved, smooth_after).max(axis=2)  # colour counts, not grey
        off = np.where(inside, np.minimum(off, difference), off)
        seen |= inside
    my, mx = int(h * MARGIN), int(w * MARGIN)
    seen[:my], seen[h - my :], seen[:, :mx], seen[:, w - mx :] = False, False, False, False
    return float((off[seen] > OFF_LEVELS).mean()) if seen.any() else 1.0


def layout_change(pictures: Sequence[np.ndarray], cache: FeatureCache | None = None) -> int | None:
    """The index of the first picture in a new layout (None: the layout stayed)."""
    cache = cache or FeatureCache(pictures)
    for index in range(1, len(pictures)):
        if _changed(pictures, cache, index - 1, index) and (
            index + 1 >= len(pictures) or _changed(pictures, cache, index - 1, index + 1)
        ):
            return index
    return None


def _changed(pictures: Sequence[np.ndarray], cache: FeatureCache, first: int, second: int) -> bool:
    """Whether the layout of picture ``second`` is not that of ``first``."""
    before, after = cache[first], cache[second]
    found = motions(before, after, MOTIONS)
    if not found:  # two textured frames with nothing in common
        return before.count >= MIN_FEATURES and after.count >= MIN_FEATURES
    moves = [m.homography for m in found]
    return unpredicted(pictures[first], pictures[second], moves) >= CHANGED_SHARE
