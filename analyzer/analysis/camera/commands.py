"""Which commands the picture can judge, and what an obedient camera shows after each one."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

# What a command asks of the picture (``Asked.kind``).
DIRECTION = "direction"  # zoom in / out until stopped: the scale grows / shrinks
RATIO = "ratio"  # zoom in / out 2x, tap_zoom: the scale doubles / halves
ABSOLUTE = "absolute"  # zoom_1x, specified_angle zoom: to a zoom ratio
STOP = "stop"  # ends a continuous zoom (judged with it, not on its own)
PALETTE = "palette"  # the thermal picture's colours change
LAYOUT = "layout"  # the picture-in-picture layout changes

# Commands act on one of these; a command ends the judgement window of the one before it
# in its group.
OPTICAL, DIGITAL, COLOURS, PIP = "optical zoom", "digital zoom", "palette", "pip"


@dataclass(frozen=True)
class Asked:
    """What a camera command asks for: ``kind``, its ``value`` (+1 / -1 for a direction,
    the factor for a ratio, the zoom ratio for an absolute zoom), the ``group`` it acts on,
    and for tap_zoom the tapped point (fractions of the half picture from the centre,
    right and down positive); for a palette, its name."""

    kind: str
    group: str
    value: float = 0.0
    tap: tuple[float, float] | None = None
    palette: str = ""

    @property
    def zoom(self) -> bool:
        return self.group in (OPTICAL, DIGITAL)

    def words(self) -> str:
        """What was asked, in a few words: "zoom in", "x2", "1x", "palette iron_red"."""
        if self.kind == DIRECTION:
            return "zoom in" if self.value > 0 else "zoom out"
        if self.kind == RATIO:
            return f"x{self.value:g}"
        if self.kind == ABSOLUTE:
            return f"{self.value:g}x"
        if self.kind == PALETTE:
            return f"palette {self.palette}"
        if self.kind == LAYOUT:
            return "the next picture-in-picture layout"
        return "stop"


_ZOOM_ACTIONS: dict[str, tuple[str, float]] = {
    "zoom_in": (DIRECTION, 1.0),
    "zoom_out": (DIRECTION, -1.0),
    "stop": (STOP, 0.0),
    "zoom_1x": (ABSOLUTE, 1.0),
    "zoom_in_2x": (RATIO, 2.0),
    "zoom_out_2x": (RATIO, 0.5),
}


def asked(fields: dict[str, Any]) -> Asked | None:
    """What a decoded command asks of the picture (None: nothing the picture shows)."""
    name = fields.get("name")
    if name in ("zoom", "digital_zoom"):
        found = _ZOOM_ACTIONS.get(str(fields.get("action")))
        if found is None:
            return None
        group = OPTICAL if name == "zoom" else DIGITAL
        return Asked(found[0], group, found[1])
    if name == "zoom_1x":
        return Asked(ABSOLUTE, OPTICAL, 1.0)
    if name == "specified_angle" and fields.get("axis") == "zoom":
        ratio = _number(fields.get("zoom"))
        return None if ratio is None or ratio <= 0 else Asked(ABSOLUTE, OPTICAL, ratio)
    if name == "tap_zoom":
        x, y = _number(fields.get("x_pct")), _number(fields.get("y_pct"))
        tap = (x / 100, y / 100) if x is not None and y is not None else None
        return Asked(RATIO, OPTICAL, 2.0, tap)
    if name == "palette":
        return Asked(PALETTE, COLOURS, palette=str(fields.get("palette", "")))
    if name == "pip_cycle":
        return Asked(LAYOUT, PIP)
    return None


def _number(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)
