"""The simulated camera's world: a flat landscape in daylight colours and in temperatures."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

LAND_PX = 2048  # the map's side in pixels
LAND_M_PER_PX = 1.0  # so it covers 2,048 m square around home, repeated beyond
MIP_LEVELS = 5  # the map at 1, 2, 4, 8 and 16 m per pixel: no shimmer far away
DETAIL_PX = 512
# Finer and finer texture on top of the map (metres per texel, contrast): the ground keeps
# detail however far the lens zooms in (an octave is at most 4 times magnified before the
# next one shows), and no two octaves repeat at the same scale.
DETAIL_M_PER_PX = (0.5, 0.5 / 4, 0.5 / 16, 0.5 / 64, 0.5 / 256)
DETAIL_CONTRAST = (0.2, 0.22, 0.22, 0.22, 0.22)
THERMAL_DETAIL_CONTRAST = (0.07, 0.06, 0.05, 0.05, 0.05)
_S = LAND_PX / 1024  # map pixels per unit of the drawing sizes below
CLOUD_SIZE = (512, 128)  # azimuth x elevation texels of the sky
SKY_HORIZON = (0.80, 0.85, 0.90)
SKY_ZENITH = (0.33, 0.52, 0.80)
HAZE = (0.78, 0.82, 0.86)
HAZE_M = 3000.0  # the distance over which the ground fades about two thirds into haze

# Daylight colours (RGB, 0..1) and temperatures (0 cold .. 1 hot) of what the map holds.
CROPS = (
    (0.45, 0.58, 0.24),
    (0.66, 0.63, 0.32),
    (0.55, 0.43, 0.28),
    (0.35, 0.47, 0.20),
    (0.75, 0.69, 0.40),
    (0.43, 0.55, 0.32),
    (0.52, 0.36, 0.22),
)
GRASS = (0.37, 0.51, 0.24)
WATER = (0.16, 0.27, 0.42)
ROAD = (0.43, 0.43, 0.41)
TRACK = (0.58, 0.50, 0.38)
TREE = (0.15, 0.30, 0.13)
ROOFS = ((0.60, 0.24, 0.20), (0.47, 0.47, 0.50), (0.67, 0.36, 0.24), (0.80, 0.78, 0.74))
CARS = ((0.85, 0.1, 0.1), (0.9, 0.9, 0.9), (0.1, 0.1, 0.12), (0.2, 0.3, 0.7))


@dataclass(frozen=True)
class World:
    """The maps the camera samples: ``colour`` (RGB, uint8) and ``temperature`` (float32,
    0 cold .. 1 hot) at each mip level, the ``detail`` octaves (float32, -1..1) and the
    sky's ``clouds`` (float32, 0..1)."""

    colour: tuple[np.ndarray, ...]
    temperature: tuple[np.ndarray, ...]
    detail: tuple[np.ndarray, ...]
    clouds: np.ndarray
    m_per_px: float = LAND_M_PER_PX


@functools.lru_cache(maxsize=2)
def make_world(seed: int = 7) -> World:
    """The same world for the same seed (made once per process, in about a second)."""
    rng = np.random.default_rng(seed)
    colour = np.empty((LAND_PX, LAND_PX, 3), np.uint8)
    colour[:] = _rgb(GRASS)
    heat = np.full((LAND_PX, LAND_PX), _hot(0.45), np.uint8)  # drawn as 8 bits, smoothly
    _fields(rng, colour, heat)
    _lakes(rng, colour, heat)
    _roads(rng, colour, heat)
    _woods(rng, colour, heat)
    _villages(rng, colour, heat)
    light = 0.85 + 0.3 * _noise(rng, LAND_PX, 1.1, low=2)
    lit = np.clip(colour * light[..., None], 0, 255).astype(np.uint8)
    temperature = heat.astype(np.float32) / 255.0
    temperature += 0.08 * (_noise(rng, LAND_PX, 1.0, low=2) - 0.5)
    np.clip(temperature, 0.0, 1.0, out=temperature)
    detail = tuple(
        (2.0 * _noise(rng, DETAIL_PX, 0.9, low=2) - 1.0).astype(np.float32) for _ in DETAIL_M_PER_PX
    )
    return World(_mips(lit), _mips(temperature), detail, _clouds(rng))


def _rgb(colour: tuple[float, ...]) -> tuple[int, ...]:
    return tuple(round(v * 255) for v in colour)


def _hot(value: float) -> int:
    """A temperature (0..1) as drawn on the 8-bit heat map."""
    return round(float(value) * 255)


def _mips(image: np.ndarray) -> tuple[np.ndarray, ...]:
    levels = [image]
    for _ in range(MIP_LEVELS - 1):
        levels.append(cv2.pyrDown(levels[-1], borderType=cv2.BORDER_WRAP))
    return tuple(levels)


def _noise(rng: np.random.Generator, size: int, exponent: float, low: int = 1) -> np.ndarray:
    """Tileable noise whose amplitude falls as 1/f^exponent, scaled to 0..1 (float32)."""
    white = rng.standard_normal((size, size))
    fy = np.fft.fftfreq(size)[:, None]
    fx = np.fft.rfftfreq(size)[None, :]
    radius = np.sqrt(fx * fx + fy * fy) * size
    shape = np.where(radius >= low, 1.0 / np.maximum(radius, 1.0) ** exponent, 0.0)
    field = np.fft.irfft2(np.fft.rfft2(white) * shape, s=(size, size))
    field -= field.min()
    field /= max(float(field.max()), 1e-9)
    return field.astype(np.float32)


def _poly(image: np.ndarray, points: np.ndarray, value: tuple[int, ...] | int) -> None:
    cv2.fillPoly(image, [np.round(points * 16).astype(np.int32)], value, cv2.LINE_AA, shift=4)


def _rectangle(cx: float, cy: float, w: float, h: float, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    corners = np.array([[-w, -h], [w, -h], [w, h], [-w, h]]) / 2
    return corners @ np.array([[c, s], [-s, c]]) + (cx, cy)


def _fields(rng: np.random.Generator, colour: np.ndarray, heat: np.ndarray) -> None:
    for _ in range(520):
        cx, cy = rng.uniform(0, LAND_PX, 2)
        w, h = rng.uniform(25, 120, 2) * _S
        angle = rng.normal(0.0, 0.25) + rng.choice([0.0, np.pi / 2])
        shade = np.array(CROPS[rng.integers(len(CROPS))]) * rng.uniform(0.85, 1.15)
        points = _rectangle(cx, cy, w, h, angle)
        _poly(colour, points, _rgb(tuple(shade)))
        _poly(heat, points, _hot(rng.uniform(0.35, 0.6)))
        rows = int(rng.integers(0, 12))
        for row in range(rows):  # furrows across the field
            offset = (row - (rows - 1) / 2) * h / max(rows, 1)
            c, s = np.cos(angle), np.sin(angle)
            furrow = _rectangle(cx - s * offset, cy + c * offset, w, 0.6 * _S, angle)
            _poly(colour, furrow, _rgb(tuple(shade * 0.8)))


def _lakes(rng: np.random.Generator, colour: np.ndarray, heat: np.ndarray) -> None:
    for _ in range(3):
        centre = (int(rng.uniform(0.2, 0.8) * LAND_PX), int(rng.uniform(0.2, 0.8) * LAND_PX))
        axes = (int(rng.uniform(25, 70) * _S), int(rng.uniform(15, 45) * _S))
        angle = float(rng.uniform(0, 180))
        cv2.ellipse(colour, centre, axes, angle, 0, 360, _rgb(WATER), -1, cv2.LINE_AA)
        cv2.ellipse(heat, centre, axes, angle, 0, 360, _hot(0.12), -1, cv2.LINE_AA)


def _path(rng: np.random.Generator, steps: int, turn: float) -> np.ndarray:
    points = [rng.uniform(0, LAND_PX, 2)]
    heading = rng.uniform(0, 2 * np.pi)
    for _ in range(steps):
        heading += rng.normal(0.0, turn)
        points.append(points[-1] + 24.0 * _S * np.array([np.cos(heading), np.sin(heading)]))
    return np.round(np.array(points) * 16).astype(np.int32)


def _roads(rng: np.random.Generator, colour: np.ndarray, heat: np.ndarray) -> None:
    for number in range(16):
        road = number < 9
        path = _path(rng, 60, 0.12 if road else 0.35)
        width = int((4 if road else 2) * _S)
        shade = _rgb(ROAD if road else TRACK)
        cv2.polylines(colour, [path], False, shade, width, cv2.LINE_AA, shift=4)
        cv2.polylines(heat, [path], False, _hot(0.68 if road else 0.5), width, cv2.LINE_AA, 4)
        if road:  # cars on it: small and hot
            for index in rng.integers(0, len(path), 6):
                x, y = path[index] / 16
                car = _rectangle(float(x), float(y), 4.4, 2.0, float(rng.uniform(0, np.pi)))
                _poly(colour, car, _rgb(CARS[int(rng.integers(len(CARS)))]))
                _poly(heat, car, 255)


def _woods(rng: np.random.Generator, colour: np.ndarray, heat: np.ndarray) -> None:
    dark = _rgb((0.08, 0.12, 0.07))
    for _ in range(22):
        cx, cy = rng.uniform(0, LAND_PX, 2)
        spread = rng.uniform(8, 40) * _S
        for x, y in rng.normal((cx, cy), spread, (160, 2)):
            radius = int(rng.integers(1, 4) * _S)
            centre = (int(x * 16), int(y * 16))
            shade = _rgb(tuple(np.array(TREE) * rng.uniform(0.7, 1.3)))
            cv2.circle(colour, centre, (radius + 1) * 16, dark, -1, cv2.LINE_AA, shift=4)
            cv2.circle(colour, centre, radius * 16, shade, -1, cv2.LINE_AA, shift=4)
            cv2.circle(heat, centre, radius * 16, _hot(0.3), -1, cv2.LINE_AA, shift=4)


def _villages(rng: np.random.Generator, colour: np.ndarray, heat: np.ndarray) -> None:
    shadow = _rgb((0.12, 0.12, 0.1))
    for village in range(4):
        # the first village lies beside home, under the orbit: something to look at
        if village == 0:
            cx, cy = LAND_PX / 2 + 40 * _S, LAND_PX / 2 - 30 * _S
        else:
            cx, cy = rng.uniform(0, LAND_PX, 2)
        for _ in range(70):
            x, y = rng.normal((cx, cy), 28 * _S, 2)
            w, h = rng.uniform(4, 11, 2) * _S
            angle = float(rng.normal(0.0, 0.15))
            _poly(colour, _rectangle(x + 1.5 * _S, y + 1.5 * _S, w, h, angle), shadow)
            roof = ROOFS[int(rng.integers(len(ROOFS)))]
            _poly(colour, _rectangle(x, y, w, h, angle), _rgb(roof))
            _poly(colour, _rectangle(x, y, w, 0.6 * _S, angle), _rgb(tuple(v * 0.7 for v in roof)))
            _poly(heat, _rectangle(x, y, w, h, angle), _hot(rng.uniform(0.7, 0.92)))


def _clouds(rng: np.random.Generator) -> np.ndarray:
    width, height = CLOUD_SIZE
    field = _noise(rng, width, 1.0, low=2)[:height, :]
    return np.clip((field - 0.45) * 3.0, 0.0, 1.0).astype(np.float32)
