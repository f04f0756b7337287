"""The thermal image in colour: the fifteen palettes of the dual-sensor camera as lookup tables."""

from __future__ import annotations

import functools

import numpy as np

from analyzer.protocol.command_table import PALETTES

# Each palette: (position 0 cold .. 1 hot, RGB 0..255) stops, interpolated between them.
_STOPS: dict[str, tuple[tuple[float, tuple[int, int, int]], ...]] = {
    "black_hot": ((0.0, (255, 255, 255)), (1.0, (0, 0, 0))),
    "white_hot": ((0.0, (0, 0, 0)), (1.0, (255, 255, 255))),
    "iron_red": (
        (0.0, (0, 0, 16)),
        (0.25, (90, 0, 140)),
        (0.5, (200, 40, 60)),
        (0.75, (250, 150, 0)),
        (1.0, (255, 255, 220)),
    ),
    "rainbow": (
        (0.0, (0, 0, 140)),
        (0.2, (0, 90, 255)),
        (0.4, (0, 220, 200)),
        (0.6, (120, 240, 0)),
        (0.8, (255, 200, 0)),
        (1.0, (230, 0, 0)),
    ),
    "lava": (
        (0.0, (0, 0, 0)),
        (0.25, (20, 20, 120)),
        (0.5, (170, 0, 40)),
        (0.75, (255, 120, 0)),
        (1.0, (255, 255, 150)),
    ),
    "rainbow_enhanced": (
        (0.0, (40, 0, 80)),
        (0.14, (0, 0, 255)),
        (0.28, (0, 200, 255)),
        (0.42, (0, 255, 80)),
        (0.57, (200, 255, 0)),
        (0.71, (255, 160, 0)),
        (0.85, (255, 0, 60)),
        (1.0, (255, 200, 255)),
    ),
    "molten_metal": (
        (0.0, (0, 0, 0)),
        (0.3, (0, 40, 120)),
        (0.55, (200, 0, 160)),
        (0.8, (255, 140, 40)),
        (1.0, (255, 255, 200)),
    ),
    "blue_red": ((0.0, (0, 40, 255)), (0.5, (235, 235, 235)), (1.0, (255, 20, 0))),
    "amber": ((0.0, (0, 0, 0)), (1.0, (255, 190, 0))),
    "amber_reversed": ((0.0, (255, 190, 0)), (1.0, (0, 0, 0))),
    "ice_blue": ((0.0, (0, 0, 20)), (0.4, (0, 60, 200)), (0.75, (80, 220, 255)), (1.0, (255,) * 3)),
    "high_contrast": (
        (0.0, (0, 0, 0)),
        (0.4, (30, 30, 30)),
        (0.6, (225, 225, 225)),
        (1.0, (255, 255, 255)),
    ),
    "grayscale_reversed": (
        (0.0, (255, 255, 255)),
        (0.5, (70, 70, 70)),
        (1.0, (25, 25, 25)),
    ),
    "high_temperature_red": (
        (0.0, (0, 0, 0)),
        (0.7, (200, 200, 200)),
        (0.75, (255, 60, 0)),
        (1.0, (255, 0, 0)),
    ),
    "cryogenic_blue": (
        (0.0, (0, 60, 255)),
        (0.25, (40, 110, 220)),
        (0.3, (70, 70, 70)),
        (1.0, (255, 255, 255)),
    ),
}
assert set(_STOPS) == set(PALETTES.values())


@functools.cache
def palette_table(name: str) -> np.ndarray:
    """The 256 x 3 RGB lookup table of a palette (white_hot for a name it does not know)."""
    stops = _STOPS.get(name, _STOPS["white_hot"])
    where = np.linspace(0.0, 1.0, 256)
    positions = [p for p, _ in stops]
    table = np.stack(
        [np.interp(where, positions, [c[i] for _, c in stops]) for i in range(3)], axis=1
    )
    return np.round(table).astype(np.uint8)


def colourize(temperature: np.ndarray, palette: str) -> np.ndarray:
    """The thermal picture (RGB uint8) of temperatures 0..1 in ``palette``."""
    index = np.clip(temperature * 255.0 + 0.5, 0, 255).astype(np.uint8)
    return palette_table(palette)[index]
