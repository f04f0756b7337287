"""What is drawn over the camera's picture, as shapes in picture fractions and as
``foxglove.ImageAnnotations`` in a picture's pixels."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from analyzer.scene.state import IMAGE_MAX, GimbalState
from analyzer.scene.stroke_font import GLYPH_HEIGHT, text_segments, text_width

# foxglove.PointsAnnotationType
LINE_LOOP = 2
LINE_LIST = 4
BOX_COLOUR = (0.25, 1.0, 0.3, 1.0)
TAP_COLOUR = (0.2, 0.85, 1.0, 1.0)
TEXT_COLOUR = (1.0, 1.0, 1.0, 1.0)
TEXT_BACKGROUND = (0.0, 0.0, 0.0, 0.6)
TRANSPARENT = (0.0, 0.0, 0.0, 0.0)
TAP_DIAMETER = 0.05  # of the picture's height
TEXT_SIZE = 1 / 22  # of the picture's height
MIN_TEXT_PX = 10.0


@dataclass(frozen=True, slots=True)
class Overlay:
    """The overlay at one moment: the tracking box (centre x, y and size as 0..1 of the
    picture's width and height), the tap points (0..1) and the text line."""

    box: tuple[float, float, float, float] | None
    taps: tuple[tuple[float, float], ...]
    text: str


def overlay(state: GimbalState) -> Overlay:
    box = None
    if state.box is not None:
        b = state.box
        box = (b.x / IMAGE_MAX, b.y / IMAGE_MAX, b.width / IMAGE_MAX, b.height / IMAGE_MAX)
    return Overlay(box, tuple((t.u, t.v) for t in state.taps), state.text())


def box_corners(
    box: tuple[float, float, float, float], width: int, height: int
) -> tuple[float, float, float, float]:
    """Left, top, right, bottom pixels of a box on a ``width`` x ``height`` picture."""
    cx, cy, w, h = box[0] * width, box[1] * height, box[2] * width, box[3] * height
    return cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2


def text_size(height: int) -> float:
    return max(MIN_TEXT_PX, round(height * TEXT_SIZE))


def line_width(height: int) -> float:
    """Thickness of the box and the tap circles on a picture ``height`` pixels high."""
    return max(2.0, round(height / 240))


@dataclass(frozen=True, slots=True)
class TextPlace:
    """Where the text line goes: its backing rectangle (left, top, right, bottom) and the
    stroke font's scale (pixels per grid unit), its top left corner and stroke width."""

    rect: tuple[float, float, float, float]
    left: float
    top: float
    scale: float
    stroke: float


def text_place(text: str, height: int) -> TextPlace:
    """The text line at the picture's top left, glyphs ``text_size`` pixels high."""
    size = text_size(height)
    scale = size / GLYPH_HEIGHT
    pad = size * 0.4
    rect = (pad, pad, pad * 3 + text_width(text, scale), pad * 3 + size)
    return TextPlace(rect, pad * 2, pad * 2, scale, max(1.0, round(scale * 0.7, 1)))


def _rectangle(
    stamp: dict[str, int],
    rect: tuple[float, float, float, float],
    outline: tuple[float, float, float, float],
    fill: tuple[float, float, float, float],
    thickness: float,
) -> dict[str, Any]:
    """A closed outline of the rectangle (left, top, right, bottom), filled with ``fill``."""
    left, top, right, bottom = rect
    return {
        "timestamp": stamp,
        "type": LINE_LOOP,
        "points": [
            _point(left, top),
            _point(right, top),
            _point(right, bottom),
            _point(left, bottom),
        ],
        "outline_color": _colour(outline),
        "outline_colors": [],
        "fill_color": _colour(fill),
        "thickness": thickness,
    }


def stroked_text(shapes: Overlay, height: int, stamp: dict[str, int]) -> list[dict[str, Any]]:
    """The text line as points annotations (a filled backing box, the glyphs' segments)."""
    place = text_place(shapes.text, height)
    backing = _rectangle(stamp, place.rect, TEXT_BACKGROUND, TEXT_BACKGROUND, 1.0)
    points = []
    for a, b in text_segments(shapes.text, place.left, place.top, place.scale):
        points += [_point(*a), _point(*b)]
    glyphs = {
        "timestamp": stamp,
        "type": LINE_LIST,
        "points": points,
        "outline_color": _colour(TEXT_COLOUR),
        "outline_colors": [],
        "fill_color": _colour(TRANSPARENT),
        "thickness": place.stroke,
    }
    return [backing, glyphs]


def _colour(rgba: tuple[float, float, float, float]) -> dict[str, float]:
    return {"r": rgba[0], "g": rgba[1], "b": rgba[2], "a": rgba[3]}


def _point(x: float, y: float) -> dict[str, float]:
    return {"x": round(x, 2), "y": round(y, 2)}


def image_annotations(
    shapes: Overlay, width: int, height: int, stamp: dict[str, int], *, stroked: bool = False
) -> dict[str, Any]:
    """The ``foxglove.ImageAnnotations`` of ``shapes`` on a ``width`` x ``height`` picture,
    every field of the schema given. The text line is a text annotation, or with
    ``stroked`` line segments of the stroke font (Foxglove Studio 1.48's Image panel draws
    points and circles but no text annotations)."""
    points = []
    if shapes.box is not None:
        corners = box_corners(shapes.box, width, height)
        points.append(_rectangle(stamp, corners, BOX_COLOUR, TRANSPARENT, line_width(height)))
    circles = [
        {
            "timestamp": stamp,
            "position": _point(u * width, v * height),
            "diameter": round(TAP_DIAMETER * height, 2),
            "thickness": line_width(height),
            "fill_color": _colour(TRANSPARENT),
            "outline_color": _colour(TAP_COLOUR),
        }
        for u, v in shapes.taps
    ]
    if stroked:
        return {
            "circles": circles,
            "points": [*points, *stroked_text(shapes, height, stamp)],
            "texts": [],
        }
    size = text_size(height)
    texts = [
        {
            "timestamp": stamp,
            "position": _point(size * 0.5, size * 1.3),
            "text": shapes.text,
            "font_size": size,
            "text_color": _colour(TEXT_COLOUR),
            "background_color": _colour(TEXT_BACKGROUND),
        }
    ]
    return {"circles": circles, "points": points, "texts": texts}
