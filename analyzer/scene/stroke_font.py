"""A small stroke font: the overlay's text line as line segments, for viewers that draw lines
but no text (Foxglove Studio 1.48's Image panel) and for the report's pictures."""

from __future__ import annotations

import itertools
from collections.abc import Iterator

# Glyphs on a grid 4 wide and 6 high (y down), as polylines; each character advances ADVANCE.
GLYPH_WIDTH = 4.0
GLYPH_HEIGHT = 6.0
ADVANCE = 6.0
_TL, _TR, _ML, _MR, _BL, _BR = (0, 0), (4, 0), (0, 3), (4, 3), (0, 6), (4, 6)
Polyline = tuple[tuple[float, float], ...]
GLYPHS: dict[str, tuple[Polyline, ...]] = {
    "0": ((_TL, _TR, _BR, _BL, _TL), (_BL, _TR)),
    "1": (((1, 1), (2, 0), (2, 6)), ((1, 6), (3, 6))),
    "2": ((_TL, _TR, _MR, _ML, _BL, _BR),),
    "3": ((_TL, _TR, _BR, _BL), (_ML, _MR)),
    "4": ((_TL, _ML, _MR), (_TR, _BR)),
    "5": ((_TR, _TL, _ML, _MR, _BR, _BL),),
    "6": ((_TR, _TL, _BL, _BR, _MR, _ML),),
    "7": ((_TL, _TR, (1, 6)),),
    "8": ((_TL, _TR, _BR, _BL, _TL), (_ML, _MR)),
    "9": ((_MR, _ML, _TL, _TR, _BR, _BL),),
    ".": (((1.5, 5.2), (2.5, 5.2), (2.5, 6), (1.5, 6), (1.5, 5.2)),),
    "-": (((0.5, 3), (3.5, 3)),),
    "+": (((0.5, 3), (3.5, 3)), ((2, 1.5), (2, 4.5))),
    "?": (((0, 1.5), (1, 0), (3, 0), (4, 1), (4, 2), (2, 3.2), (2, 4.5)), ((2, 5.4), (2, 6))),
    "x": (((0.5, 2.5), (3.5, 6)), ((3.5, 2.5), (0.5, 6))),
    "P": ((_BL, _TL, _TR, _MR, _ML),),
    "Y": ((_TL, (2, 3), _TR), ((2, 3), (2, 6))),
    "Z": ((_TL, _TR, _BL, _BR),),
    " ": (),
}


def text_width(text: str, scale: float) -> float:
    """Width of ``text`` drawn with glyphs ``scale`` pixels per grid unit."""
    return (len(text) * ADVANCE - (ADVANCE - GLYPH_WIDTH)) * scale if text else 0.0


def text_segments(
    text: str, left: float, top: float, scale: float
) -> Iterator[tuple[tuple[float, float], tuple[float, float]]]:
    """The line segments of ``text`` with its top left corner at ``left``, ``top``; characters
    the font lacks are drawn as '?'."""
    for i, char in enumerate(text):
        x0 = left + i * ADVANCE * scale
        for line in GLYPHS.get(char, GLYPHS["?"]):
            for (ax, ay), (bx, by) in itertools.pairwise(line):
                yield (x0 + ax * scale, top + ay * scale), (x0 + bx * scale, top + by * scale)
