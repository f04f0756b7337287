"""The ArduPilot driver's parameters, written once: its Lua block, usage lines and page section."""

from __future__ import annotations

from dataclasses import dataclass

from analyzer.export.literals import lua_string
from analyzer.protocol.ids import CAN_BITRATE

PARAM_TABLE_KEY = 148  # no script shipped with ArduPilot uses it (tests/ardupilot_scripts.py)
PARAM_TABLE_PREFIX = "VSH_"
MESSAGE_PREFIX = "VSH: "  # what the driver's messages to the GCS start with
DEFAULT_ZOOM_MAX = 30  # the zoom ratio of a 100 % zoom request (30x models)


@dataclass(frozen=True)
class DriverParameter:
    """One of the driver's own parameters, as ArduPilot documents a script's (@Param)."""

    name: str  # without the table's prefix
    default: int
    display_name: str
    description: str  # a sentence
    user: str  # Standard or Advanced
    values: tuple[tuple[int, str], ...] = ()
    limits: tuple[int, int] | None = None  # @Range
    usage: str = ""  # the line of the driver's "How to use" (after the name)

    @property
    def full_name(self) -> str:
        return PARAM_TABLE_PREFIX + self.name


PARAMETERS: tuple[DriverParameter, ...] = (
    DriverParameter(
        "CAN_DRV",
        1,
        "Gimbal CAN driver",
        "Scripting CAN driver the gimbal is on: 1 is the driver whose CAN_Dx_PROTOCOL is 10 "
        "(Scripting), 2 the one whose CAN_Dx_PROTOCOL is 12 (Scripting2)",
        "Standard",
        values=((1, "First scripting CAN driver"), (2, "Second scripting CAN driver")),
        usage="= 2 when the gimbal is on the second scripting CAN driver (CAN_D2_PROTOCOL = 12)",
    ),
    DriverParameter(
        "DEBUG",
        0,
        "Gimbal driver debug",
        "Debug messages to the GCS: 1 counters every 5 s, 2 the gimbal's attitude too",
        "Advanced",
        values=((0, "Disabled"), (1, "Enabled"), (2, "Enabled with attitude reporting")),
        usage="= 1 sends counters to the GCS every 5 s, 2 the gimbal's attitude too",
    ),
    DriverParameter(
        "ZOOM_MAX",
        DEFAULT_ZOOM_MAX,
        "Gimbal camera zoom maximum",
        "Zoom ratio of a 100% zoom request (a 0% request is 1x)",
        "Standard",
        limits=(1, 35),
        usage="= the zoom ratio of a 100 % zoom request (30 for a 30x camera)",
    ),
)


@dataclass(frozen=True)
class AutopilotParameter:
    """One of ArduPilot's own parameters the driver needs: its value, and why."""

    name: str
    value: int
    why: str
    note: str = ""  # "(or more)", "(optional)"


AUTOPILOT_PARAMETERS: tuple[AutopilotParameter, ...] = (
    AutopilotParameter("SCR_ENABLE", 1, "run Lua scripts"),
    AutopilotParameter("SCR_HEAP_SIZE", 120000, "memory for the scripts", "(or more)"),
    AutopilotParameter("CAN_P1_DRIVER", 1, "CAN1 port served by the first CAN driver"),
    AutopilotParameter("CAN_P1_BITRATE", CAN_BITRATE, "the gimbal's bit rate (1 Mbit/s)"),
    AutopilotParameter(
        "CAN_D1_PROTOCOL", 10, "the first CAN driver is a scripting driver (Scripting)"
    ),
    AutopilotParameter("MNT1_TYPE", 9, "the first mount is driven by a script (Scripting)"),
    AutopilotParameter(
        "CAM1_TYPE", 7, "the first camera is driven by a script (Scripting), for camera control"
    ),
    AutopilotParameter(
        "CAN_P1_OPTIONS",
        1,
        "LogAllFrames: the bus's frames go to the DataFlash log",
        "(optional)",
    ),
)


def lua_block() -> list[str]:
    """The parameter table (add_table / add_param), then each parameter's @Param block
    and its binding, as ArduPilot's drivers declare them."""
    prefix = MESSAGE_PREFIX
    lines = [
        "-- parameters (generated)",
        f"local PARAM_TABLE_KEY = {PARAM_TABLE_KEY}  -- unique among ArduPilot's scripts",
        f"local PARAM_TABLE_PREFIX = {lua_string(PARAM_TABLE_PREFIX)}",
        f"assert(param:add_table(PARAM_TABLE_KEY, PARAM_TABLE_PREFIX, {len(PARAMETERS)}), "
        f'"{prefix}could not add param table")',
    ]
    for number, p in enumerate(PARAMETERS, 1):
        lines.append(
            f'assert(param:add_param(PARAM_TABLE_KEY, {number}, "{p.name}", {p.default}), '
            f'"{prefix}could not add {p.full_name}")'
        )
    for p in PARAMETERS:
        lines += ["", "--[[", f"  // @Param: {p.full_name}"]
        lines.append(f"  // @DisplayName: {p.display_name}")
        lines.append(f"  // @Description: {p.description}")
        if p.values:
            lines.append("  // @Values: " + ",".join(f"{v}:{text}" for v, text in p.values))
        if p.limits is not None:
            lines.append(f"  // @Range: {p.limits[0]} {p.limits[1]}")
        lines += [f"  // @User: {p.user}", "--]]"]
        lines.append(f'local {p.full_name} = Parameter("{p.full_name}")')
    return [*lines, ""]


def _value(p: AutopilotParameter) -> str:
    return f"{p.value} {p.note}" if p.note else str(p.value)


def autopilot_usage() -> list[str]:
    """The "How to use" lines about the autopilot's parameters and the driver's."""
    lines = [
        "    Connect the gimbal's CAN H / CAN L (pins 2 / 1 of its 7-pin connector) to the",
        "    autopilot's CAN1 (or CAN2) port",
    ]
    lines += [f"    Set {p.name} = {_value(p)}: {p.why}" for p in AUTOPILOT_PARAMETERS]
    lines.append(
        f"    For CAN2: CAN_P2_DRIVER = 2, CAN_P2_BITRATE = {CAN_BITRATE}, CAN_D2_PROTOCOL = 12"
    )
    lines.append("    Copy this script to the SD card's APM/scripts directory and reboot")
    lines += [f"    {p.full_name} {p.usage}" for p in PARAMETERS]
    return lines


def page_section() -> list[str]:
    """The parameters part of the driver's page (one section per parameter)."""
    lines = ["# Parameters", ""]
    for p in PARAMETERS:
        text = f"{p.description} (default {p.default})."
        if p.values:
            text += " " + "; ".join(f"{v}: {what}" for v, what in p.values) + "."
        if p.limits is not None:
            text += f" From {p.limits[0]} to {p.limits[1]}."
        lines += [f"## {p.full_name}", "", text, ""]
    lines += [
        "# How to use",
        "",
        "Connect the gimbal's CAN H / CAN L to the autopilot's CAN1 port and set:",
        "",
        "| parameter | value | why |",
        "|---|---|---|",
        *(f"| {p.name} | {_value(p)} | {p.why} |" for p in AUTOPILOT_PARAMETERS),
        "",
        f"For CAN2 set CAN_P2_DRIVER = 2, CAN_P2_BITRATE = {CAN_BITRATE}, CAN_D2_PROTOCOL = 12",
        f"(Scripting2) and {PARAM_TABLE_PREFIX}CAN_DRV = 2.",
        "",
    ]
    return lines
