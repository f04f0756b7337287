"""How the picture moved between two frames: ORB features, matched, a homography by RANSAC.

Why features and not Fourier-Mellin phase correlation: the picture is judged while the
gimbal turns and the aircraft flies, so two frames share only part of their content, seen
in perspective; cameras burn text, a centre cross and the tracker's box into the picture,
which do not move with the scene. Phase correlation of the whole picture measures all of
that at once (the fixed overlays pull the scale toward 1), while matched features with
RANSAC keep only the points that agree on one motion of the scene and say how many did: a
picture with too little texture shows as too few inliers instead of a wrong number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

FEATURES = 1500
MIN_FEATURES = 60  # fewer than this in a picture: too little texture to measure
MIN_INLIERS = 25  # matches that agree on one motion before it is believed
RATIO_TEST = 0.8  # Lowe's ratio: a match must be clearly better than the second best
REPROJECTION_PX = 2.5
MAX_LINK_SCALE = 1.8  # one measurement spans at most this change of scale either way (more is
# measured, by fewer points, less well)

_CLAHE = cv2.createCLAHE(clipLimit=2.0, tileGridSize=(8, 8))
_ORB = cv2.ORB_create(  # type: ignore[attr-defined]
    nfeatures=FEATURES, scaleFactor=1.2, nlevels=8, edgeThreshold=19, fastThreshold=8
)
_MATCHER = cv2.BFMatcher(cv2.NORM_HAMMING)


@dataclass(frozen=True, eq=False)
class Features:
    """The ORB keypoints (N x 2, pixels) and descriptors of one picture, and its size."""

    points: np.ndarray
    descriptors: np.ndarray | None
    width: int
    height: int

    @property
    def count(self) -> int:
        return len(self.points)

    @property
    def centre(self) -> np.ndarray:
        return np.array([(self.width - 1) / 2, (self.height - 1) / 2, 1.0])


@dataclass(frozen=True)
class Motion:
    """The homography taking the first picture's pixels to the second's, the matches
    that agree with it (``inliers``) of those found, and the scale it means."""

    homography: np.ndarray
    inliers: int
    matches: int
    scale: float


def features(rgb: np.ndarray) -> Features:
    """ORB features of a picture, its local contrast evened out first (CLAHE), so that a
    dull patch of ground or a thermal picture still gives points."""
    gray = rgb if rgb.ndim == 2 else cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    keypoints, descriptors = _ORB.detectAndCompute(_CLAHE.apply(gray), None)
    points = np.array([k.pt for k in keypoints], np.float32).reshape(-1, 2)
    return Features(points, descriptors, gray.shape[1], gray.shape[0])


def motion(first: Features, second: Features) -> Motion | None:
    """The motion from ``first`` to ``second``; None when too few matches agree on one
    (too little texture, too little overlap, or a change of scale too large to follow)."""
    found = motions(first, second, 1)
    return found[0] if found else None


def motions(first: Features, second: Features, most: int = 2) -> list[Motion]:
    """Up to ``most`` motions between two pictures, the one most matches agree on first,
    then one of the matches left (a picture-in-picture inset moves on its own)."""
    if first.descriptors is None or second.descriptors is None:
        return []
    if min(first.count, second.count) < MIN_FEATURES:
        return []
    pairs = _MATCHER.knnMatch(first.descriptors, second.descriptors, k=2)
    good = [p[0] for p in pairs if len(p) == 2 and p[0].distance < RATIO_TEST * p[1].distance]
    source = first.points[[m.queryIdx for m in good]].reshape(-1, 2)
    target = second.points[[m.trainIdx for m in good]].reshape(-1, 2)
    found: list[Motion] = []
    while len(found) < most and len(source) >= MIN_INLIERS:
        homography, mask = cv2.findHomography(source, target, cv2.USAC_MAGSAC, REPROJECTION_PX)
        if homography is None or mask is None:
            break
        agree = mask.reshape(-1).astype(bool)
        if int(agree.sum()) < MIN_INLIERS:
            break
        scale = centre_scale(homography, first, second)
        if scale is None or not 1 / MAX_LINK_SCALE <= scale <= MAX_LINK_SCALE:
            break
        found.append(Motion(homography, int(agree.sum()), len(good), scale))
        source, target = source[~agree], target[~agree]
    return found


def local_scale(homography: np.ndarray, point: np.ndarray) -> float | None:
    """How much the homography magnifies lengths at ``point`` (x, y, 1): the square root
    of its Jacobian's determinant, det(H) / w^3 for the point's w = h3 . p."""
    w = float(homography[2] @ point)
    determinant = float(np.linalg.det(homography))
    if w == 0 or determinant <= 0 or w < 0:
        return None
    return math.sqrt(determinant / w**3)


def centre_scale(homography: np.ndarray, first: Features, second: Features) -> float | None:
    """The change of scale between two pictures, as a zoom changes it: the geometric mean
    of the magnification at the first picture's centre and at the point that lands on the
    second one's centre. For a lens that turns and zooms about its own centre (the picture
    then moves by a homography K2 R K1^-1) this is exactly f2 / f1, however it turned:
    the two magnifications are (f2 / f1) cos^-1.5 and cos^+1.5 of the angle turned."""
    at_first = local_scale(homography, first.centre)
    try:
        back = np.linalg.solve(homography, second.centre)
    except np.linalg.LinAlgError:
        return None
    if back[2] == 0:
        return None
    at_second = local_scale(homography, back / back[2])
    if at_first is None or at_second is None:
        return None
    return math.sqrt(at_first * at_second)


def where(homography: np.ndarray, x: float, y: float) -> tuple[float, float] | None:
    """Where a pixel of the first picture lands in the second (None: behind the lens)."""
    point = homography @ np.array([x, y, 1.0])
    if point[2] <= 0:
        return None
    return float(point[0] / point[2]), float(point[1] / point[2])
