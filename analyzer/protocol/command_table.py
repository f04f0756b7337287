"""Command table of chapter 2.1: one row per command; drives decode, encode, schemas, docs."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from analyzer.protocol.fields import Field
from analyzer.protocol.ids import COMPONENT_DUAL_SENSOR, COMPONENT_GIMBAL


def D(n: int) -> int:
    """Offset in the 8 CAN bytes of DATAn (DATA1 is CAN byte 2, after S_ID and CMD)."""
    return n + 1


@dataclass(frozen=True)
class CommandRow:
    """One row of the command table."""

    s_id: int
    cmd: int
    name: str
    title: str  # the document's name for it
    params: tuple[Field, ...] = ()
    selector: Field | None = None  # a DATA byte that picks one of ``variants``
    variants: Mapping[int, tuple[Field, ...]] = field(default_factory=dict)
    description: str = ""

    def all_fields(self) -> tuple[Field, ...]:
        fields = list(self.params)
        if self.selector is not None:
            fields.append(self.selector)
        for variant in self.variants.values():
            fields.extend(variant)
        return tuple(fields)


# -- shared value sets ----------------------------------------------------------------------


def _speed(name: str, n: int, what: str) -> Field:
    return Field(
        name,
        D(n),
        "s16",
        div=100,
        unit="deg/s",
        minimum=-10000,
        maximum=10000,
        default=0,
        description=what,
    )


def _box_centre(n: int, axis: str) -> Field:
    return Field(
        axis,
        D(n),
        "u16",
        minimum=0,
        maximum=8191,
        description=f"{'horizontal' if axis == 'x' else 'vertical'} coordinate of the box centre "
        "(0,0 top left, 8191,8191 bottom right)",
    )


def _tap_point(n: int, axis: str) -> Field:
    return Field(
        f"{axis}_pct",
        D(n),
        "s16",
        div=100,
        unit="%",
        minimum=-10000,
        maximum=10000,
        description=f"{'horizontal' if axis == 'x' else 'vertical'} distance of the target "
        "from the image centre (-100 % top/left, 100 % bottom/right)",
    )


def _box_size(n: int, name: str, what: str, expected: int | None = None) -> Field:
    return Field(
        name,
        D(n),
        "u8",
        mul=16,
        unit="px",
        expected=expected,
        default=None if expected is None else expected * 16,
        description=f"{what} of the box, sent divided by 16 (0..8191 image coordinates)",
    )


ZOOM_ACTIONS = {
    1: "zoom_in",
    2: "zoom_out",
    3: "stop",
    4: "zoom_1x",
    5: "zoom_in_2x",
    6: "zoom_out_2x",
}
FOCUS_ACTIONS = {1: "focus_plus", 2: "focus_minus", 3: "stop", 4: "auto_focus"}
DIGITAL_ZOOM_ACTIONS = {1: "zoom_in", 2: "zoom_out", 3: "stop"}
RECORDING_ACTIONS = {1: "start", 2: "stop"}
SNAPSHOT_MODES = {1: "single", 2: "continuous", 3: "time_lapse", 4: "timed", 5: "stop"}
ANGLE_AXES = {1: "yaw", 2: "pitch", 3: "zoom"}
COORDINATE_SYSTEMS = {1: "airframe"}
PALETTES = {
    0x0: "black_hot",
    0x1: "white_hot",
    0x2: "iron_red",
    0x3: "rainbow",
    0x4: "lava",
    0x5: "rainbow_enhanced",
    0x6: "molten_metal",
    0x7: "blue_red",
    0x8: "amber",
    0x9: "amber_reversed",
    0xA: "ice_blue",
    0xB: "high_contrast",
    0xC: "grayscale_reversed",
    0xD: "high_temperature_red",
    0xE: "cryogenic_blue",
}

# Parameter sets that the gimbal and the dual-sensor camera share.
TAP_POINT = (_tap_point(1, "x"), _tap_point(3, "y"))
TRACKING_BOX = (
    _box_centre(1, "x"),
    _box_centre(3, "y"),
    _box_size(5, "width", "horizontal length"),
    _box_size(6, "height", "vertical width"),
)

G = COMPONENT_GIMBAL
DS = COMPONENT_DUAL_SENSOR

COMMANDS: tuple[CommandRow, ...] = (
    # -- gimbal / optical camera (S_ID 0x0F) -------------------------------------------------
    CommandRow(
        G,
        0x01,
        "tap_zoom",
        "TapZoom",
        TAP_POINT,
        description="Turn the target point to the image centre and zoom in twice.",
    ),
    CommandRow(
        G, 0x02, "forward", "Forward", description="Return the gimbal to the forward position."
    ),
    CommandRow(G, 0x03, "zoom_1x", "One Key to 1x Image", description="Zoom back to 1x."),
    CommandRow(
        G,
        0x04,
        "gimbal_control",
        "Gimbal Control",
        (
            _speed("pan_speed_dps", 1, "pan speed, positive = right"),
            _speed("tilt_speed_dps", 3, "tilt speed, positive = up"),
        ),
        description="Rotate at the given speeds; repeat about every 50 ms to keep moving.",
    ),
    CommandRow(
        G,
        0x05,
        "tracking",
        "Tracking",
        TRACKING_BOX,
        description="Start tracking the target in the given box.",
    ),
    CommandRow(G, 0x06, "tracking_stop", "Tracking stop", description="Stop target tracking."),
    CommandRow(
        G, 0x07, "look_down", "One key to down", description="Point the camera straight down."
    ),
    CommandRow(
        G,
        0x08,
        "specified_angle",
        "Specified Angle",
        (
            Field(
                "coordinate_system",
                D(4),
                "u8",
                labels=COORDINATE_SYSTEMS,
                other_label="geodetic",
                default="geodetic",
                description="DATA4: 1 = airframe coordinate system, anything else geodetic",
            ),
        ),
        selector=Field("axis", D(1), "u8", labels=ANGLE_AXES, description="control type"),
        variants={
            1: (
                Field(
                    "yaw_deg",
                    D(2),
                    "s16",
                    div=10,
                    unit="deg",
                    minimum=0,
                    maximum=3600,
                    description="yaw angle",
                ),
            ),
            2: (
                Field(
                    "pitch_deg",
                    D(2),
                    "s16",
                    div=10,
                    unit="deg",
                    minimum=-1000,
                    maximum=600,
                    description="pitch angle",
                ),
            ),
            3: (
                Field(
                    "zoom",
                    D(2),
                    "s16",
                    div=100,
                    unit="x",
                    minimum=100,
                    maximum=3500,
                    soft_maximum=3000,
                    soft_note="above 30x: only 35x models reach it",
                    description="zoom ratio",
                ),
            ),
        },
        description="Turn to an absolute yaw or pitch angle, or set the zoom ratio.",
    ),
    CommandRow(
        G,
        0x10,
        "snapshot",
        "Snapshot",
        (),
        selector=Field("mode", D(1), "u8", labels=SNAPSHOT_MODES, description="snapshot mode"),
        variants={
            1: (),
            2: (Field("shots", D(2), "u8", description="number of continuous shots"),),
            3: (Field("delay_s", D(2), "u8", unit="s", description="time-lapse delay"),),
            4: (Field("timer_s", D(2), "u8", unit="s", description="timed-shot timer"),),
            5: (),
        },
        description="Take pictures: single, continuous, time-lapse or timed, or stop.",
    ),
    CommandRow(
        G,
        0x11,
        "recording",
        "Recording",
        (Field("action", D(1), "u8", labels=RECORDING_ACTIONS, description="start or stop"),),
        description="Start or stop video recording.",
    ),
    CommandRow(
        G,
        0x12,
        "zoom",
        "Zoom",
        (Field("action", D(1), "u8", labels=ZOOM_ACTIONS, description="zoom action"),),
        description="Optical zoom in / out / stop / 1x / 2x steps.",
    ),
    CommandRow(
        G,
        0x13,
        "focus",
        "Focus",
        (Field("action", D(1), "u8", labels=FOCUS_ACTIONS, description="focus action"),),
        description="Focus + / - / stop / auto focus.",
    ),
    CommandRow(
        G,
        0x14,
        "tap_focus",
        "TapFocus",
        (
            _box_centre(1, "x"),
            _box_centre(3, "y"),
            _box_size(5, "width", "horizontal length", expected=25),
            _box_size(6, "height", "vertical width", expected=25),
        ),
        description="Focus on the given point (box size fixed at 25 x 16 px).",
    ),
    CommandRow(G, 0xF0, "quick_calibration", "Quick Calibration", description="Quick calibration."),
    # -- dual-sensor camera (S_ID 0x1F) --------------------------------------------------------
    CommandRow(
        DS,
        0x01,
        "tap_zoom",
        "TapZoom (Dual-Sensor)",
        TAP_POINT,
        description="Turn the target point to the image centre and zoom in twice.",
    ),
    CommandRow(
        DS,
        0x02,
        "palette",
        "Color Palettes (Dual-Sensor)",
        (Field("palette", D(1), "u8", labels=PALETTES, description="thermal colour palette"),),
        description="Select the thermal colour palette.",
    ),
    CommandRow(
        DS,
        0x03,
        "pip_cycle",
        "Picture-in-picture mode cycle switching",
        description="Cycle the picture-in-picture mode.",
    ),
    CommandRow(
        DS,
        0x04,
        "gimbal_control",
        "Gimbal Control (Dual-Sensor)",
        (
            _speed("pan_speed_dps", 1, "yaw (pan) speed, positive = right"),
            _speed("tilt_speed_dps", 3, "pitch (tilt) speed, positive = up"),
        ),
        description="Rotate at the given speeds; repeat about every 50 ms to keep moving.",
    ),
    CommandRow(
        DS,
        0x05,
        "tracking",
        "Tracking (Dual-Sensor)",
        TRACKING_BOX,
        description="Start tracking the target in the given box.",
    ),
    CommandRow(
        DS,
        0x07,
        "tracking_stop",
        "Stop Tracking (Dual-Sensor)",
        description="Stop target tracking.",
    ),
    CommandRow(
        DS,
        0x12,
        "digital_zoom",
        "Digital Zoom (Dual-Sensor)",
        (Field("action", D(1), "u8", labels=DIGITAL_ZOOM_ACTIONS, description="zoom action"),),
        description="Digital zoom in / out / stop.",
    ),
)

BY_CODE: dict[tuple[int, int], CommandRow] = {(c.s_id, c.cmd): c for c in COMMANDS}
BY_NAME: dict[str, tuple[CommandRow, ...]] = {}
for _c in COMMANDS:
    BY_NAME[_c.name] = (*BY_NAME.get(_c.name, ()), _c)
COMMAND_NAMES: tuple[str, ...] = tuple(BY_NAME)
