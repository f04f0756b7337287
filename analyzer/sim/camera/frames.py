"""One picture of a stream: the sensors at the zoom asked, composed as the PiP mode says."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from analyzer.sim.camera.render import View, hfov_for, render_thermal, render_visible
from analyzer.sim.camera.thermal import colourize
from analyzer.sim.camera.world import World
from analyzer.sim.model import HFOV_1X

THERMAL_HFOV = 32.0  # the thermal lens: fixed focal length (digital zoom only)
MAIN, SUB, THERMAL = "main", "sub", "thermal"  # what a stream shows
# The picture-in-picture layouts of the main and sub streams, as pip_cycle steps through them.
PIP_LAYOUTS = (
    "visible",
    "visible with a thermal inset",
    "thermal with a visible inset",
    "visible and thermal side by side",
)
INSET = 1 / 3  # an inset's width, of the picture's
BOX_COLOUR = (40, 255, 60)


@dataclass(frozen=True)
class Shot:
    """What the camera shows at one moment: where the lens is and looks, the optical and
    digital zoom, the thermal palette, the PiP layout and the tracker's box (fractions of
    the picture; (0, 0) when not tracking)."""

    east_m: float
    north_m: float
    up_m: float
    yaw_deg: float
    pitch_deg: float
    zoom: float = 1.0
    digital_zoom: float = 1.0
    palette: str = "white_hot"
    pip_mode: int = 0
    tracking_box: tuple[float, float] = (0.0, 0.0)

    def view(self, hfov: float) -> View:
        return View(self.east_m, self.north_m, self.up_m, self.yaw_deg, self.pitch_deg, hfov)


class Gain:
    """A thermal camera's automatic gain: the scene's coldest to hottest (1st to 99th
    percentile) spread over the whole palette, following the scene in about a second (a
    gain that jumped with every frame would flicker)."""

    def __init__(self, follow: float = 0.1) -> None:
        self.follow = follow  # the share of the way to the new range taken each frame
        self.range: tuple[float, float] | None = None

    def __call__(self, temperature: np.ndarray) -> np.ndarray:
        low, high = (float(v) for v in np.percentile(temperature[::4, ::4], (1.0, 99.0)))
        if self.range is not None:
            old_low, old_high = self.range
            low = old_low + self.follow * (low - old_low)
            high = old_high + self.follow * (high - old_high)
        self.range = (low, high)
        return (temperature - low) / max(high - low, 0.05)


def picture(
    world: World, shot: Shot, kind: str, width: int, height: int, gain: Gain | None = None
) -> np.ndarray:
    """The RGB picture (uint8, height x width x 3) a stream of ``kind`` shows; ``gain``
    is the stream's thermal gain (a fresh one, for a single picture, when None)."""
    gain = gain or Gain()
    if kind == THERMAL:
        image = _sensor(world, shot, width, height, True, gain)
    else:
        image = _composed(world, shot, width, height, gain)
        _crosshair(image)
    _tracking_box(image, shot.tracking_box)
    return image


def _sensor(
    world: World,
    shot: Shot,
    width: int,
    height: int,
    thermal: bool,
    gain: Gain,
    crop: float = 1.0,
) -> np.ndarray:
    """One sensor's picture; digital zoom renders fewer pixels and scales them up, as a
    camera crops its sensor (``crop`` narrows the view further, for side by side)."""
    hfov = THERMAL_HFOV if thermal else hfov_for(shot.zoom, HFOV_1X)
    digital = max(1.0, shot.digital_zoom)
    narrowed = hfov_for(digital / crop, hfov)
    w = max(16, round(width / digital))
    h = max(9, round(height / digital))
    view = shot.view(narrowed)
    if thermal:
        image = colourize(gain(_blurred(render_thermal(world, view, w, h))), shot.palette)
    else:
        image = render_visible(world, view, w, h)
    if (w, h) != (width, height):
        image = cv2.resize(image, (width, height), interpolation=cv2.INTER_LINEAR)
    return image


def _blurred(temperature: np.ndarray) -> np.ndarray:
    """A thermal core's optics and pixels are soft."""
    return cv2.GaussianBlur(temperature, (0, 0), 0.8)


def _composed(world: World, shot: Shot, width: int, height: int, gain: Gain) -> np.ndarray:
    mode = shot.pip_mode % len(PIP_LAYOUTS)
    if mode == 3:
        half = width // 2
        # each half shows the middle of its sensor's view, in its own field of view
        left = _sensor(world, shot, half, height, False, gain, crop=0.5)
        right = _sensor(world, shot, width - half, height, True, gain, crop=0.5)
        image = np.concatenate([left, right], axis=1)
        image[:, half - 1 : half + 1] = 255
        return image
    image = _sensor(world, shot, width, height, mode == 2, gain)
    if mode in (1, 2):
        w = int(width * INSET) // 2 * 2
        h = int(height * INSET) // 2 * 2
        inset = _sensor(world, shot, w, h, mode == 1, gain)
        x, y = width - w - 8, 8
        image[y - 2 : y + h + 2, x - 2 : x + w + 2] = 255
        image[y : y + h, x : x + w] = inset
    return image


def _crosshair(image: np.ndarray) -> None:
    """The camera's centre mark, drawn into the picture as real cameras do."""
    h, w = image.shape[:2]
    cx, cy = w // 2, h // 2
    arm, gap = max(6, w // 50), max(2, w // 160)
    colour = (235, 235, 235)
    cv2.line(image, (cx - arm, cy), (cx - gap, cy), colour, 1)
    cv2.line(image, (cx + gap, cy), (cx + arm, cy), colour, 1)
    cv2.line(image, (cx, cy - arm), (cx, cy - gap), colour, 1)
    cv2.line(image, (cx, cy + gap), (cx, cy + arm), colour, 1)


def _tracking_box(image: np.ndarray, box: tuple[float, float]) -> None:
    """The tracker's box: the gimbal keeps the target in the middle of the picture."""
    if box[0] <= 0 or box[1] <= 0:
        return
    h, w = image.shape[:2]
    bw, bh = max(8, int(box[0] * w)), max(8, int(box[1] * h))
    top_left = (w // 2 - bw // 2, h // 2 - bh // 2)
    cv2.rectangle(image, top_left, (top_left[0] + bw, top_left[1] + bh), BOX_COLOUR, 2)
