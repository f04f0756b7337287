"""ArduPilot's scripts and its CI's Lua checks, as facts: the parameter table keys its scripts
use, and luacheck's configuration made the way ArduPilot's is.

Source: ArduPilot at commit 2a929aeaf47cc8eec8ed4e9af2c57a3b0d5ffb0d (2025-10-26):

- the keys are the first argument of every ``param:add_table`` in its 248 Lua files
  (``libraries/AP_Scripting/{applets,drivers,examples}``, ``Tools/AP_Periph/Web/scripts``);
  a key held in a variable was read from its assignment (``arming-checks.lua`` adds 170 to
  170 + 6 and 179, one table per vehicle);
- its CI runs ``Tools/scripts/run_luacheck.sh``: Debian's ``lua-check`` with
  ``libraries/AP_Scripting/tests/luacheck.lua``, which ignores the warnings below and makes
  the read-only globals of the ``ArduPilot`` std from ``docs/docs.lua`` (every global it
  sets, a table's fields with ``other_fields = false``) plus a few enums added by hand.
  ``tests/data/ardupilot-docs-globals.json`` keeps those globals, read the same way.
"""

from __future__ import annotations

import json
from pathlib import Path

from analyzer.ardupilot.lua_build import ARDUPILOT_COMMIT

GLOBALS_FILE = Path(__file__).resolve().parent / "data" / "ardupilot-docs-globals.json"

# key -> the scripts that add a parameter table with it
TABLE_KEYS: dict[int, tuple[str, ...]] = {
    7: ("applets/plane_ship_landing.lua",),
    8: ("applets/VTOL-quicktune.lua",),
    9: ("applets/plane_package_place.lua",),
    10: ("applets/RockBlock.lua", "examples/config_profiles.lua"),
    11: ("examples/plane_guided_follow.lua",),
    12: ("applets/plane_precland.lua",),
    13: ("examples/EFI_tester.lua",),
    14: ("applets/BattEstimate.lua",),
    15: ("applets/rover-quicktune.lua",),
    16: ("examples/sim_arming_pos.lua",),
    31: ("applets/revert_param.lua",),
    35: ("examples/ship_vel_match.lua",),
    36: ("drivers/EFI_SkyPower.lua",),
    37: ("drivers/EFI_HFE.lua",),
    38: ("drivers/mount-djirs2-driver.lua",),
    39: ("drivers/mount-viewpro-driver.lua",),
    40: ("drivers/EFI_Halo6000.lua",),
    41: ("drivers/EFI_DLA.lua",),
    42: ("drivers/Generator_SVFFI.lua",),
    43: ("drivers/INF_Inject.lua",),
    44: ("drivers/Hobbywing_DataLink.lua",),
    45: ("drivers/BattMon_ANX.lua",),
    46: ("examples/net_test.lua",),
    47: ("applets/net_webserver.lua", "Tools/AP_Periph/Web/scripts/pppgw_webui.lua"),
    48: ("drivers/EFI_NMEA2k.lua",),
    49: ("applets/BatteryTag.lua",),
    51: ("examples/BQ40Z_bms_shutdown.lua",),
    52: ("drivers/EFI_DLA64.lua",),
    70: ("applets/Aerobatics/FixedWing/plane_aerobatics.lua",),
    71: ("applets/Aerobatics/FixedWing/plane_aerobatics.lua", "examples/copter-posoffset.lua"),
    72: (
        "applets/Aerobatics/FixedWing/RateBased/sport_aerobatics.lua",
        "examples/copter_deploy.lua",
        "examples/param_add.lua",
    ),
    73: (
        "applets/Aerobatics/FixedWing/RateBased/sport_aerobatics.lua",
        "applets/Heli_idle_control.lua",
        "examples/gen_control.lua",
    ),
    74: ("examples/glide_into_wind.lua",),
    75: ("applets/motor_failure_test.lua", "examples/copter-fast-descent.lua"),
    76: ("applets/QuadPlane_Low_Alt_FW_mode_prevention.lua",),
    77: ("examples/fw_vtol_failsafe.lua",),
    78: ("applets/mount-poi.lua",),
    79: ("examples/copter_alt_offset.lua",),
    80: ("applets/UniversalAutoLand.lua", "applets/winch-control.lua"),
    81: ("applets/ahrs-source-extnav-optflow.lua",),
    82: ("applets/copter-slung-payload.lua",),
    83: ("examples/orbit_follow.lua",),
    84: ("applets/copter_terrain_brake.lua",),
    85: ("applets/camera-change-setting.lua",),
    86: ("applets/copter-deadreckon-home.lua",),
    87: ("applets/ahrs-set-origin.lua",),
    88: ("applets/follow-target-send.lua",),
    89: ("drivers/UltraMotion.lua",),
    90: ("applets/video-stream-information.lua",),
    91: ("drivers/torqeedo-torqlink.lua",),
    92: ("applets/param-set.lua",),
    93: ("examples/qnh_alt.lua",),
    101: ("examples/plane_guided_terrain.lua",),
    102: ("applets/throttle_kill.lua", "examples/plane-callout-alt.lua"),
    104: ("drivers/TOFSense-M/TOFSense-M_CAN.lua",),
    106: ("applets/quadplane_terrain_avoid.lua", "drivers/LTE_modem.lua"),
    109: ("drivers/TOFSense-M/TOFSense-M_Serial.lua",),
    117: ("examples/rover-TerrainDetector.lua",),
    123: ("applets/plane_follow.lua",),
    135: ("examples/servo_slew.lua",),
    136: ("examples/ESC_slew_rate.lua",),
    138: ("examples/wrap32_test.lua",),
    139: ("applets/x-quad-cg-allocation.lua",),
    142: ("drivers/VSPeak_flow_meter.lua",),
    **{170 + n: ("applets/arming-checks.lua",) for n in range(7)},
    179: ("applets/arming-checks.lua",),
    193: ("applets/advance-wp.lua",),
}
TABLE_KEY_RANGE = (0, 200)  # param:add_table's table_key (AP_Param, bindings.desc)

# libraries/AP_Scripting/tests/luacheck.lua
LUACHECK_IGNORE = ("111", "113", "212/_.*", "631", "611", "612", "614")
LUACHECK_ENUMS: dict[str, tuple[str, ...]] = {
    "mission": ("MISSION_COMPLETE", "MISSION_RUNNING", "MISSION_STOPPED"),
    "terrain": ("TerrainStatusOK", "TerrainStatusUnhealthy", "TerrainStatusDisabled"),
    "gps": (
        "GPS_OK_FIX_3D_RTK_FIXED",
        "GPS_OK_FIX_3D_RTK_FLOAT",
        "GPS_OK_FIX_3D_DGPS",
        "GPS_OK_FIX_3D",
        "GPS_OK_FIX_2D",
        "NO_FIX",
        "NO_GPS",
    ),
}


def docs_globals() -> dict[str, list[str] | None]:
    """docs.lua's globals: a table's field names, None for a function."""
    data = json.loads(GLOBALS_FILE.read_text(encoding="utf-8"))
    assert ARDUPILOT_COMMIT in data["source"], "the globals come from another commit"
    globals_: dict[str, list[str] | None] = data["globals"]
    return globals_


def luacheck_config() -> str:
    """A luacheck configuration as ArduPilot's luacheck.lua builds it (std lua53+ArduPilot)."""
    entries = []
    for name, fields in sorted(docs_globals().items()):
        if fields is None:
            entries.append(f"  [{name!r}] = {{other_fields = false}},")
            continue
        names = sorted({*fields, *LUACHECK_ENUMS.get(name, ())})
        inner = " ".join(f"[{f!r}] = {{other_fields = false}}," for f in names)
        entries.append(f"  [{name!r}] = {{other_fields = false, fields = {{{inner}}}}},")
    ignore = ", ".join(f'"{code}"' for code in LUACHECK_IGNORE)
    return "\n".join(
        [
            f"-- ArduPilot's luacheck rules (libraries/AP_Scripting/tests/luacheck.lua @ "
            f"{ARDUPILOT_COMMIT[:12]})",
            f"ignore = {{{ignore}}}",
            "stds.ArduPilot = {read_globals = {",
            *entries,
            "}}",
            'std = "lua53+ArduPilot"',
            "",
        ]
    )
