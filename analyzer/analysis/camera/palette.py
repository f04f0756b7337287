"""Did the thermal picture change its palette? The colours of each frame and the next, compared.

A palette maps each temperature to one colour, so a thermal picture uses the palette's
colours and no others. A new palette shows from one frame to the next as colours the
frame before did not use (a share of pixels whose colour the other frame has no pixel
near); from one frame to the next the scene itself hardly changes, however the gimbal
turns, so its colours stay (comparing frames a second apart would not do: the camera's
automatic gain recolours a scene that changed). Palettes that share their colours (the
grey ones, amber and its reverse) differ in how bright each temperature is: a reversed
one shows as a brightness histogram that matches the other frame's only when flipped,
another curve as histograms that overlap less than a frame and the next ever do.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

Y_STEP, C_STEP = 16, 8  # colour bins: brightness 16 levels wide, chroma 8
MIN_SHARE = 0.0005  # a colour bin is used when it holds this share of the pixels
# Measured on the simulated camera's frames 1/15 s apart, the gimbal turning 20 deg/s and
# the aircraft flying 12 m/s from 15 m up: in one palette at most 3 % of a frame is in new
# colours and its brightness histogram overlaps the one before by 81 % or more (94 % from
# 80 m up); the palettes most alike differ by more.
NEW_COLOURS = 0.05  # this share of one frame in colours the other never uses: changed
HISTOGRAM_BINS = 64
MIN_OVERLAP = 0.75
FLIP_MARGIN = 0.1


def _bins(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's colour bin (an index), and the chroma channels (Cr, Cb)."""
    ycc = cv2.cvtColor(rgb, cv2.COLOR_RGB2YCrCb).reshape(-1, 3)
    y = ycc[:, 0].astype(np.int32) // Y_STEP
    cr = ycc[:, 1].astype(np.int32) // C_STEP
    cb = ycc[:, 2].astype(np.int32) // C_STEP
    return (y * 32 + cr) * 32 + cb, ycc[:, 1:]


def _used(bins: np.ndarray) -> np.ndarray:
    """The colour bins a picture uses, grown by one bin every way (16 x 32 x 32 booleans)."""
    counts = np.bincount(bins, minlength=16 * 32 * 32).reshape(16, 32, 32)
    used = (counts >= MIN_SHARE * len(bins)).astype(np.uint8)
    grown = cv2.dilate(used.reshape(16, 32 * 32), np.ones((3, 1), np.uint8)).reshape(16, 32, 32)
    grown = np.stack([cv2.dilate(plane, np.ones((3, 3), np.uint8)) for plane in grown])
    return grown.reshape(-1).astype(bool)


def new_colours(before: np.ndarray, after: np.ndarray) -> float:
    """The larger share of either picture in colours the other does not use."""
    bins_a, _ = _bins(before)
    bins_b, _ = _bins(after)
    used_a, used_b = _used(bins_a), _used(bins_b)
    return max(float((~used_a[bins_b]).mean()), float((~used_b[bins_a]).mean()))


def _histogram(rgb: np.ndarray) -> np.ndarray:
    gray = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    counts = np.bincount(gray.reshape(-1) // (256 // HISTOGRAM_BINS), minlength=HISTOGRAM_BINS)
    smooth = np.convolve(counts.astype(np.float64), np.ones(3) / 3, mode="same")
    return smooth / max(1.0, float(smooth.sum()))


def palette_change(pictures: Sequence[np.ndarray]) -> int | None:
    """The index of the first picture in a new palette (None: the palette stayed)."""
    for index in range(1, len(pictures)):
        if palette_changed(pictures[index - 1], pictures[index]):
            return index
    return None


def palette_changed(before: np.ndarray, after: np.ndarray) -> bool:
    """Whether the palette changed between two thermal pictures a moment apart."""
    if new_colours(before, after) >= NEW_COLOURS:
        return True
    a, b = _histogram(before), _histogram(after)
    same = float(np.minimum(a, b).sum())
    return same < MIN_OVERLAP or float(np.minimum(a, b[::-1]).sum()) > same + FLIP_MARGIN
