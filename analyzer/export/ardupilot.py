"""The protocol tables as an ArduPilot Lua mount driver (CAN), and the page of its parameters."""

from __future__ import annotations

from importlib import resources

from analyzer.protocol.codec import find_command
from analyzer.protocol.crc import crc16
from analyzer.protocol.feedback import LAYOUTS
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import (
    CAN_BITRATE,
    CONTROL_ID,
    FEEDBACK_ID,
    FEEDBACK_MESSAGE_SIZE,
    HEADER,
)
from analyzer.protocol.uav import STATUS_FRAMES
from analyzer.version import __version__

__all__ = ["DRIVER_NAME", "PARAMETERS", "lua_text", "markdown_text"]

DRIVER_NAME = "mount-viewsheen-driver.lua"
PARAM_TABLE_KEY = 87  # the key of the driver's parameter table (unique among scripts)
PARAM_TABLE_PREFIX = "VSH_"
DEFAULT_ZOOM_MAX = 30  # the zoom ratio of a 100 % zoom request (30x models)
TRACK_POINT_SIZE = 512  # a tracked point gets a box this big (image coordinates)
SEGMENT_SIZE = 8  # a feedback message arrives as CAN frames of this many bytes

# The commands the driver sends (all of the gimbal's component, S_ID 0x0F).
SENT_COMMANDS = (
    "gimbal_control",
    "specified_angle",
    "snapshot",
    "recording",
    "zoom",
    "focus",
    "tracking",
    "tracking_stop",
)

# The driver's own parameters: name, default, what it is.
PARAMETERS: tuple[tuple[str, float, str], ...] = (
    (
        "CAN_DRV",
        1,
        "scripting CAN driver the gimbal is on: 1 = the driver whose CAN_Dx_PROTOCOL is 10 "
        "(Scripting), 2 = the one whose CAN_Dx_PROTOCOL is 12 (Scripting2)",
    ),
    ("DEBUG", 0, "debug messages to the GCS: 1 counters every 5 s, 2 the gimbal's attitude too"),
    (
        "ZOOM_MAX",
        DEFAULT_ZOOM_MAX,
        "zoom ratio of a 100 % zoom request (a 0 % request is 1x); 1 to 35",
    ),
)

# ArduPilot's own parameters the driver needs, and why.
AUTOPILOT_PARAMETERS: tuple[tuple[str, str, str], ...] = (
    ("SCR_ENABLE", "1", "run Lua scripts"),
    ("SCR_HEAP_SIZE", "120000 (or more)", "memory for the scripts"),
    ("CAN_P1_DRIVER", "1", "CAN1 port served by the first CAN driver"),
    ("CAN_P1_BITRATE", f"{CAN_BITRATE}", "the gimbal's bit rate (1 Mbit/s)"),
    ("CAN_D1_PROTOCOL", "10", "the first CAN driver is a scripting driver (Scripting)"),
    ("MNT1_TYPE", "9", "the first mount is driven by a script (Scripting)"),
    ("CAM1_TYPE", "7", "the first camera is driven by a script (Scripting), for camera control"),
    ("CAN_P1_OPTIONS", "1 (optional)", "LogAllFrames: the bus's frames go to the DataFlash log"),
)


def _lua_str(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return f'"{escaped}"'


def _int(value: int) -> str:
    """An integer literal that stays an integer in ArduPilot's Lua (32-bit integers)."""
    return "-2147483647 - 1" if value == -(2**31) else str(value)


def _field(f: Field, *, labels: bool = False) -> str:
    """A field as the Lua body reads it: 0-based offset, size, scale and raw limits (and the
    codes of its labels, for the commands the driver sends)."""
    lo, hi = f.raw_limits()
    items = [
        f"off={f.offset}",
        f"size={f.size}",
        f"signed={'true' if f.kind.startswith('s') else 'false'}",
        f"div={f.div}",
        f"mul={f.mul}",
        f"min={_int(lo)}",
        f"max={_int(hi)}",
    ]
    if labels and f.labels is not None:
        pairs = dict(f.labels.items())
        if f.other_label is not None:
            pairs[0] = f.other_label  # what encode_command writes for the other label
        assert all(name.isidentifier() for name in pairs.values()), pairs
        codes = ", ".join(f"{name}={raw}" for raw, name in sorted(pairs.items()))
        items.append(f"labels={{{codes}}}")
    note = f.description + (f" [{f.unit}]" if f.unit else "")
    return "{" + ", ".join(items) + "}" + f",  -- {note}"


def _table(name: str, entries: list[tuple[str, list[str]]]) -> list[str]:
    """``local NAME = {...}``: each entry's head (``key = {...,``) and its fields."""
    lines = [f"local {name} = {{"]
    for head, fields in entries:
        lines.append(f"  {head}fields={{")
        lines += [f"    {field}" for field in fields]
        lines.append("  }},")
    lines.append("}")
    return lines


def _commands() -> list[str]:
    entries = []
    for name in SENT_COMMANDS:
        row = find_command(name, s_id="gimbal")
        head = f"{name} = {{s_id=0x{row.s_id:02X}, cmd=0x{row.cmd:02X}, "
        entries.append((head, [f"{f.name} = {_field(f, labels=True)}" for f in row.all_fields()]))
    return _table("COMMANDS", entries)


def _feedback() -> list[str]:
    entries = [
        (
            f"[0x{length:02X}] = {{name={_lua_str(layout.name)}, crc_off={layout.crc_offset}, ",
            [f"{f.name} = {_field(f)}" for f in layout.layout.fields],
        )
        for length, layout in LAYOUTS.items()
    ]
    return _table("FEEDBACK", entries)


def _status() -> list[str]:
    entries = [
        (
            f"{status.name} = {{id=0x{can_id:08X}, ",
            [f"{f.name} = {_field(f)}" for f in status.layout.fields],
        )
        for can_id, status in STATUS_FRAMES.items()
    ]
    return _table("STATUS", entries)


def _crc_table() -> list[str]:
    # crc16 of one byte from 0 is that byte's table entry: the table of protocol/crc.py
    table = [crc16(bytes([byte]), 0) for byte in range(256)]
    rows = [
        "  " + ", ".join(f"0x{v:04X}" for v in table[i : i + 8]) + "," for i in range(0, 256, 8)
    ]
    return ["local CRC_TABLE = {", *rows, "}"]


def _header() -> list[str]:
    prefix = PARAM_TABLE_PREFIX
    return [
        f"-- {DRIVER_NAME}: gimbal mount driver on CAN for ArduPilot",
        "-- luacheck: only 0",
        "",
        "--[[",
        "  How to use",
        "    Connect the gimbal's CAN H / CAN L (pins 2 / 1 of its 7-pin connector) to the",
        "    autopilot's CAN1 (or CAN2) port",
        "    Set CAN_P1_DRIVER = 1 (First driver), CAN_P1_BITRATE = 1000000",
        "    Set CAN_D1_PROTOCOL = 10 (Scripting) for the first scripting CAN driver",
        f"      (or CAN_D2_PROTOCOL = 12 (Scripting2) and {prefix}CAN_DRV = 2 for the second)",
        "    Set SCR_ENABLE = 1 to enable scripting, SCR_HEAP_SIZE = 120000 (or higher)",
        "    Set MNT1_TYPE = 9 (Scripting) to enable the mount/gimbal scripting driver",
        "    Set CAM1_TYPE = 7 (Scripting) to control the camera (pictures, video, zoom, focus,",
        "      tracking) from ArduPilot's camera library",
        "    Copy this script to the autopilot's SD card in the APM/scripts directory and reboot",
        f"    {prefix}DEBUG = 1 sends counters to the GCS every 5 s, 2 the gimbal's attitude too",
        "",
        "  What it does",
        "    mount:get_rate_target -> gimbal_control every 50 ms, speeds 0 when the rates stop",
        "    mount:get_angle_target -> specified_angle pitch and yaw (airframe or geodetic yaw)",
        "    mount:get_location_target -> specified_angle to that point from the aircraft",
        "    camera:get_state -> snapshot, recording, zoom, focus, tracking / tracking_stop",
        "    feedback (4 CAN frames, CRC-16/MODBUS) -> mount:set_attitude_euler (body frame)",
        "    UAV attitude 10 Hz, GPS and altitude above home 5 Hz -> the gimbal (north reference)",
        "",
        "  Generated by `gimbal-analyzer export ardupilot` from the protocol's command table",
        f"  (gimbal-analyzer {__version__}): the CAN IDs, scales, ranges, field offsets and the",
        "  CRC table below come from it. Every value sent is kept inside the document's range.",
        "  Try it, or an edited copy, on the simulated gimbal with",
        f"    gimbal-analyzer demo --ardupilot {DRIVER_NAME}",
        "--]]",
        "",
    ]


def _tables() -> list[str]:
    tracking = find_command("tracking", s_id="gimbal")
    image_size = dict((f.name, f) for f in tracking.params)["x"].raw_limits()[1] + 1
    return [
        "-- protocol tables (generated)",
        f"local CONTROL_ID = 0x{CONTROL_ID:08X}  -- commands to the gimbal",
        f"local FEEDBACK_ID = 0x{FEEDBACK_ID:08X}  -- the gimbal's feedback segments",
        f"local HEADER = {{0x{HEADER[0]:02X}, 0x{HEADER[1]:02X}}}  -- start of a message",
        f"local FEEDBACK_SEGMENTS = {FEEDBACK_MESSAGE_SIZE // SEGMENT_SIZE}  "
        f"-- {FEEDBACK_MESSAGE_SIZE}-byte messages in {SEGMENT_SIZE}-byte CAN frames",
        f"local CRC_INIT = 0x{crc16(b''):04X}  -- CRC-16/MODBUS, low byte first",
        f"local IMAGE_SIZE = {image_size}  -- tracking coordinates 0 .. {image_size - 1}",
        f"local TRACK_POINT_SIZE = {TRACK_POINT_SIZE}  -- box around a tracked point",
        f"local DEFAULT_ZOOM_MAX = {DEFAULT_ZOOM_MAX}",
        f"local PARAM_TABLE_KEY = {PARAM_TABLE_KEY}",
        f"local PARAM_TABLE_PREFIX = {_lua_str(PARAM_TABLE_PREFIX)}",
        "",
        "-- fields: 0-based CAN byte offset, size, physical = raw * mul / div, raw limits",
        *_commands(),
        *_feedback(),
        *_status(),
        *_crc_table(),
        "",
    ]


def lua_text() -> str:
    """The whole driver: header, generated tables, then the fixed body."""
    body = resources.files("analyzer.export").joinpath("mount_driver.lua").read_text("utf-8")
    return "\n".join(_header() + _tables()) + "\n" + body


def markdown_text() -> str:
    """The page that goes beside the driver, as ArduPilot's drivers have one."""
    prefix = PARAM_TABLE_PREFIX
    lines = [
        "# Gimbal mount driver (CAN)",
        "",
        f"`{DRIVER_NAME}` drives the gimbal over CAN from ArduPilot's mount library",
        "(MNT1_TYPE = 9) on a scripting CAN driver. It was generated by",
        "`gimbal-analyzer export ardupilot` from the protocol's command table.",
        "",
        "# Parameters",
        "",
    ]
    for name, default, what in PARAMETERS:
        text = f"{what[0].upper()}{what[1:]} (default {default:g})."
        lines += [f"## {prefix}{name}", "", text, ""]
    lines += [
        "# How to use",
        "",
        "Connect the gimbal's CAN H / CAN L to the autopilot's CAN1 port and set:",
        "",
        "| parameter | value | why |",
        "|---|---|---|",
        *(f"| {name} | {value} | {why} |" for name, value, why in AUTOPILOT_PARAMETERS),
        "",
        f"For CAN2 set CAN_P2_DRIVER = 2, CAN_P2_BITRATE = {CAN_BITRATE}, CAN_D2_PROTOCOL = 12",
        f"(Scripting2) and {prefix}CAN_DRV = 2.",
        "",
        "Copy the script to the autopilot's SD card in the APM/scripts directory and reboot.",
        "The GCS shows `VSH: mount driver started`; `VSH: no feedback from the gimbal` when",
        "the gimbal is silent for 2 s, and `VSH: feedback dropped: N CRC, M cut` (at most",
        "every 5 s) when feedback messages arrive damaged or incomplete.",
        "",
        "# What it sends",
        "",
        "- rate targets (RC targeting): `gimbal_control` every 50 ms, pan = yaw rate, tilt =",
        "  pitch rate; one `gimbal_control` with speeds 0 when the rates stop",
        "- angle targets: `specified_angle` pitch and yaw when they change; a body-frame yaw",
        "  with the airframe flag, an earth-frame yaw (yaw lock, ROI) as a geodetic angle",
        "- location targets (ROI, GPS point): the angles to the point from the aircraft",
        "- camera (CAM1_TYPE = 7): take picture -> `snapshot`, record video -> `recording`,",
        f"  zoom rate -> `zoom`, zoom percent -> `specified_angle` zoom (1x .. {prefix}ZOOM_MAX),",
        "  focus rate / auto -> `focus`, tracking a point or a rectangle -> `tracking`,",
        "  stop tracking -> `tracking_stop`",
        "- UAV status the gimbal needs for north-referenced angles: attitude (0x0000FF13) at",
        "  10 Hz from the AHRS, GPS (0x0000FF15) from the GPS with a 3D fix and altitude",
        "  above home (0x0000FF16) at 5 Hz",
        "",
        "The gimbal's attitude feedback (four CAN frames of ID 0x030F0001, CRC checked) is",
        "reported to the mount library: pitch, and yaw as the yaw motor's angle (body frame).",
        "",
    ]
    return "\n".join(lines)
