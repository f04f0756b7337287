"""Soft, low-texture water filmed at long zoom, with the centre cross a camera burns in.

A lake seen from above has little texture: smooth ripples of low contrast, fading as the
lens zooms in. With so few features the cross drawn in every picture (it never moves)
can win RANSAC's vote between two frames, so a link between them may say the picture
kept its scale while the lens zoomed. The pictures are made here, not rendered from the
simulated world (its ground has detail at every zoom).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from analyzer.video.decode import Picture
from tests.test_camera_pictures import through_h264

SIDE_PX = 2048  # the lake's texture, square
WATER_RGB = (0.16, 0.27, 0.42)
FPS = 15
ZOOM_RATE = 6.0  # zoom ratio per second, as the simulated lens's


def lake(seed: int = 2, softness: float = 1.35, contrast: float = 0.38) -> np.ndarray:
    """Ripples whose amplitude falls as 1/f^softness, ``contrast`` either way of the
    water's colour."""
    rng = np.random.default_rng(seed)
    white = rng.standard_normal((SIDE_PX, SIDE_PX))
    fy = np.fft.fftfreq(SIDE_PX)[:, None]
    fx = np.fft.rfftfreq(SIDE_PX)[None, :]
    radius = np.sqrt(fx * fx + fy * fy) * SIDE_PX
    spectrum = np.where(radius >= 1, 1.0 / np.maximum(radius, 1.0) ** softness, 0.0)
    field = np.fft.irfft2(np.fft.rfft2(white) * spectrum, s=(SIDE_PX, SIDE_PX))
    field = (field - field.min()) / (field.max() - field.min())
    colour = np.array(WATER_RGB) * 255 * 1.6
    image = colour[None, None, :] * (1 + contrast * (2 * field[..., None] - 1))
    return np.clip(image, 0, 255).astype(np.uint8)


def view(water: np.ndarray, zoom: float, width: int = 640, height: int = 360) -> np.ndarray:
    """The lake's middle at ``zoom`` (1x: 45 % of it across), the centre cross drawn in."""
    scale = width / (water.shape[1] * 0.45 / zoom)
    warp = np.array(
        [
            [scale, 0.0, width / 2 - scale * water.shape[1] / 2],
            [0.0, scale, height / 2 - scale * water.shape[0] / 2],
        ]
    )
    flags = cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR
    image = cv2.warpAffine(water, warp, (width, height), flags=flags)
    cx, cy = width // 2, height // 2
    for (x0, y0), (x1, y1) in (
        ((cx - 12, cy), (cx - 3, cy)),
        ((cx + 3, cy), (cx + 12, cy)),
        ((cx, cy - 12), (cx, cy - 3)),
        ((cx, cy + 3), (cx, cy + 12)),
    ):
        cv2.line(image, (x0, y0), (x1, y1), (235, 235, 235), 1)
    return image


@dataclass(frozen=True)
class ZoomTo:
    """At ``at`` seconds the lens starts to zoom to ``ratio`` at ZOOM_RATE."""

    at: float
    ratio: float


def lens(moves: Sequence[ZoomTo], t: float, start: float = 1.0) -> float:
    """The zoom ratio at ``t`` of a lens at ``start`` making ``moves`` one after another."""
    zoom = start
    for index, move in enumerate(moves):
        if t < move.at:
            break
        until = min(t, moves[index + 1].at) if index + 1 < len(moves) else t
        step = ZOOM_RATE * (until - move.at)
        zoom = max(move.ratio, zoom - step) if move.ratio < zoom else min(move.ratio, zoom + step)
    return zoom


class FilmedLake:
    """A VideoSource: one stream, ``main``, of the lake as the lens zoomed, at FPS, the
    pictures through H.264 as a recording holds them."""

    def __init__(self, moves: Sequence[ZoomTo], seconds: float, water: np.ndarray) -> None:
        times = [i / FPS for i in range(math.ceil(seconds * FPS))]
        self.zooms = [lens(moves, t) for t in times]
        images = through_h264([view(water, zoom) for zoom in self.zooms])
        self.frames = [Picture(t, rgb) for t, rgb in zip(times, images, strict=True)]

    def streams(self) -> list[str]:
        return ["main"]

    def pictures(self, stream: str, start: float, end: float) -> list[Picture]:
        return [p for p in self.frames if start <= p.time <= end]

    def until(self) -> float:
        return math.inf
