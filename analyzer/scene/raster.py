"""The overlay drawn into a JPEG picture (the report's camera pictures), with PyAV alone."""

from __future__ import annotations

import itertools
import math
from fractions import Fraction
from typing import cast

import av

from analyzer.scene.overlays import (
    BOX_COLOUR,
    TAP_COLOUR,
    TAP_DIAMETER,
    TEXT_BACKGROUND,
    TEXT_COLOUR,
    Overlay,
    box_corners,
    line_width,
    text_place,
)
from analyzer.scene.stroke_font import text_segments

Colour = tuple[float, float, float, float]


class Raster:
    """An RGB picture in a bytearray (rows ``stride`` bytes apart) to draw on."""

    def __init__(self, width: int, height: int, stride: int, pixels: bytearray) -> None:
        self.width, self.height, self.stride, self.pixels = width, height, stride, pixels

    def blend(self, x: int, y: int, colour: Colour) -> None:
        if 0 <= x < self.width and 0 <= y < self.height:
            i = y * self.stride + x * 3
            a = colour[3]
            for k in range(3):
                self.pixels[i + k] = round(self.pixels[i + k] * (1 - a) + 255 * colour[k] * a)

    def fill(self, left: float, top: float, right: float, bottom: float, colour: Colour) -> None:
        for y in range(max(0, round(top)), min(self.height, round(bottom))):
            for x in range(max(0, round(left)), min(self.width, round(right))):
                self.blend(x, y, colour)

    def dot(
        self, x: float, y: float, size: float, colour: Colour, done: set[tuple[int, int]]
    ) -> None:
        """A square ``size`` pixels wide at ``x``, ``y``; ``done`` keeps pixels from being
        blended twice by one shape."""
        half = size / 2
        for py in range(math.floor(y - half + 0.5), math.floor(y + half + 0.5)):
            for px in range(math.floor(x - half + 0.5), math.floor(x + half + 0.5)):
                if (px, py) not in done:
                    done.add((px, py))
                    self.blend(px, py, colour)

    def line(
        self,
        a: tuple[float, float],
        b: tuple[float, float],
        width: float,
        colour: Colour,
        done: set[tuple[int, int]],
    ) -> None:
        steps = max(1, math.ceil(math.dist(a, b) * 2))
        for n in range(steps + 1):
            f = n / steps
            self.dot(a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, width, colour, done)


def draw(raster: Raster, overlay: Overlay) -> None:
    """The tracking box, the tap circles and the text line, as the annotations show them."""
    width, height = raster.width, raster.height
    thickness = line_width(height)
    if overlay.box is not None:
        left, top, right, bottom = box_corners(overlay.box, width, height)
        corners = [(left, top), (right, top), (right, bottom), (left, bottom)]
        done: set[tuple[int, int]] = set()
        for i, corner in enumerate(corners):
            raster.line(corner, corners[(i + 1) % 4], thickness, BOX_COLOUR, done)
    for u, v in overlay.taps:
        radius, done = TAP_DIAMETER * height / 2, set()
        steps = max(12, round(radius * 8))
        ring = [
            (u * width + radius * math.cos(2 * math.pi * n / steps),
             v * height + radius * math.sin(2 * math.pi * n / steps))
            for n in range(steps + 1)
        ]  # fmt: skip
        for a, b in itertools.pairwise(ring):
            raster.line(a, b, thickness, TAP_COLOUR, done)
    place = text_place(overlay.text, height)
    raster.fill(*place.rect, TEXT_BACKGROUND)
    done = set()
    for a, b in text_segments(overlay.text, place.left, place.top, place.scale):
        raster.line(a, b, place.stroke, TEXT_COLOUR, done)


def jpeg_with_overlay(jpeg: bytes, overlay: Overlay) -> bytes | None:
    """The JPEG picture with ``overlay`` drawn into it (None when it does not decode)."""
    try:
        decoder = cast(av.VideoCodecContext, av.CodecContext.create("mjpeg", "r"))
        frames = [*decoder.decode(av.Packet(jpeg)), *decoder.decode(None)]
        if not frames:
            return None
        rgb = frames[0].reformat(format="rgb24")
        plane = rgb.planes[0]
        raster = Raster(rgb.width, rgb.height, plane.line_size, bytearray(bytes(plane)))
        draw(raster, overlay)
        out = av.VideoFrame(rgb.width, rgb.height, "rgb24")
        target = out.planes[0]
        pixels = bytearray(target.line_size * rgb.height)
        row = rgb.width * 3
        for y in range(rgb.height):
            start = y * raster.stride
            pixels[y * target.line_size : y * target.line_size + row] = raster.pixels[
                start : start + row
            ]
        target.update(bytes(pixels))
        encoder = cast(av.VideoCodecContext, av.CodecContext.create("mjpeg", "w"))
        encoder.width, encoder.height = rgb.width, rgb.height
        encoder.pix_fmt = "yuvj420p"
        encoder.time_base = Fraction(1, 25)
        packets = [*encoder.encode(out.reformat(format="yuvj420p")), *encoder.encode(None)]
    except (av.error.FFmpegError, ValueError):
        return None
    return bytes(packets[0]) if packets else None
