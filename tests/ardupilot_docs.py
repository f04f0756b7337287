"""ArduPilot's scripting API as its docs.lua declares it: the facts the emulation is held to.

Source: ArduPilot's libraries/AP_Scripting/docs/docs.lua at commit
2a929aeaf47cc8eec8ed4e9af2c57a3b0d5ffb0d (master, 2025-10-26): every signature below is
there as written, and ``DEPRECATED`` are its ``---@deprecated`` functions (bindings.desc
gives them a ``deprecate`` text: ArduPilot warns at the first call, and that warning is the
scripting error the pre-arm check reports). The same signatures were already in docs.lua at
commit 85503302031cfab761551f4da5180b6b3c524ad6 and in bindings.desc at commit
002c901c0fd26cdeed6e8a32dd52988b8489ceed.
"""

from __future__ import annotations

from analyzer.ardupilot.lua_build import ARDUPILOT_COMMIT

DOCS_VERSION = f"docs.lua @ {ARDUPILOT_COMMIT[:12]}"

# (class, name) -> parameter names; a trailing '?' marks an optional one (a field's getter
# and setter share one name: ``frame:id()`` reads, ``frame:id(value)`` writes). The class is
# docs.lua's: '' for a global function, ``mount`` for a singleton, ``X_ud`` for a userdata.
SIGNATURES: dict[tuple[str, str], tuple[str, ...]] = {
    # manual bindings
    ("", "uint32_t"): ("value?",),
    ("uint32_t_ud", "toint"): (),
    ("uint32_t_ud", "tofloat"): (),
    ("", "millis"): (),
    ("", "micros"): (),
    ("", "print"): ("text",),
    # CAN
    ("CAN", "get_device"): ("buffer_len",),
    ("CAN", "get_device2"): ("buffer_len",),
    ("", "CANFrame"): (),
    ("CANFrame_ud", "dlc"): ("value?",),
    ("CANFrame_ud", "data"): ("index", "value?"),
    ("CANFrame_ud", "id"): ("value?",),
    ("CANFrame_ud", "isErrorFrame"): (),
    ("CANFrame_ud", "isRemoteTransmissionRequest"): (),
    ("CANFrame_ud", "isExtended"): (),
    ("CANFrame_ud", "id_signed"): (),
    ("ScriptingCANBuffer_ud", "read_frame"): (),
    ("ScriptingCANBuffer_ud", "write_frame"): ("frame", "timeout_us"),
    ("ScriptingCANBuffer_ud", "add_filter"): ("mask", "value"),
    # parameters
    ("param", "add_table"): ("table_key", "prefix", "num_params"),
    ("param", "add_param"): ("table_key", "param_num", "name", "default_value"),
    ("param", "get"): ("name",),
    ("param", "set"): ("name", "value"),
    ("", "Parameter"): ("name?",),  # Parameter() and Parameter(name)
    ("Parameter_ud", "init"): ("name",),
    ("Parameter_ud", "get"): (),
    ("Parameter_ud", "set"): ("value",),
    # geometry
    ("", "Location"): (),
    ("Location_ud", "lat"): ("value?",),
    ("Location_ud", "lng"): ("value?",),
    ("Location_ud", "alt"): ("value?",),
    ("Location_ud", "relative_alt"): ("value?",),
    ("Location_ud", "copy"): (),
    ("Location_ud", "change_alt_frame"): ("desired_frame",),
    ("Location_ud", "get_distance_NE"): ("loc",),
    ("Location_ud", "get_distance_NED"): ("loc",),
    ("Location_ud", "get_bearing"): ("loc",),
    ("Location_ud", "get_distance"): ("loc",),
    ("Vector2f_ud", "x"): ("value?",),
    ("Vector2f_ud", "y"): ("value?",),
    ("Vector2f_ud", "length"): (),
    ("Vector3f_ud", "x"): ("value?",),
    ("Vector3f_ud", "y"): ("value?",),
    ("Vector3f_ud", "z"): ("value?",),
    ("Vector3f_ud", "length"): (),
    # mount
    ("mount", "set_attitude_euler"): ("instance", "roll_deg", "pitch_deg", "yaw_deg"),
    ("mount", "get_location_target"): ("instance",),
    ("mount", "get_angle_target"): ("instance",),
    ("mount", "get_rate_target"): ("instance",),
    # camera
    ("camera", "get_state"): ("instance",),
    ("AP_Camera__camera_state_t_ud", "take_pic_incr"): (),
    ("AP_Camera__camera_state_t_ud", "recording_video"): (),
    ("AP_Camera__camera_state_t_ud", "zoom_type"): (),
    ("AP_Camera__camera_state_t_ud", "zoom_value"): (),
    ("AP_Camera__camera_state_t_ud", "focus_type"): (),
    ("AP_Camera__camera_state_t_ud", "focus_value"): (),
    ("AP_Camera__camera_state_t_ud", "tracking_type"): (),
    ("AP_Camera__camera_state_t_ud", "tracking_p1"): (),
    ("AP_Camera__camera_state_t_ud", "tracking_p2"): (),
    # vehicle state
    ("ahrs", "get_roll"): (),
    ("ahrs", "get_pitch"): (),
    ("ahrs", "get_yaw"): (),
    ("ahrs", "get_roll_rad"): (),
    ("ahrs", "get_pitch_rad"): (),
    ("ahrs", "get_yaw_rad"): (),
    ("ahrs", "get_location"): (),
    ("ahrs", "get_home"): (),
    ("ahrs", "get_relative_position_D_home"): (),
    ("gps", "num_sensors"): (),
    ("gps", "primary_sensor"): (),
    ("gps", "status"): ("instance",),
    ("gps", "location"): ("instance",),
    # GCS
    ("gcs", "send_text"): ("severity", "text"),
}

# (class, name) -> what to use instead: docs.lua's ---@deprecated (bindings.desc's text)
DEPRECATED: dict[tuple[str, str], str] = {
    ("Location_ud", "get_vector_from_origin_NEU"): (
        "Use get_vector_from_origin_NEU_cm or get_vector_from_origin_NEU_m"
    ),
    ("rangefinder", "ground_clearance_cm_orient"): "Use ground_clearance_orient (in metres)",
    ("rangefinder", "min_distance_cm_orient"): "Use min_distance_orient (in metres)",
    ("rangefinder", "max_distance_cm_orient"): "Use max_distance_orient (in metres)",
    ("rangefinder", "distance_cm_orient"): "Use distance_orient (in metres)",
    ("ahrs", "get_yaw"): "Use get_yaw_rad",
    ("ahrs", "get_pitch"): "Use get_pitch_rad",
    ("ahrs", "get_roll"): "Use get_roll_rad",
}

# The enum docs.lua gives gps (gps.GPS_OK_FIX_3D = 3, ...).
GPS_CONSTANTS = {
    "NO_GPS": 0,
    "NO_FIX": 1,
    "GPS_OK_FIX_2D": 2,
    "GPS_OK_FIX_3D": 3,
    "GPS_OK_FIX_3D_DGPS": 4,
    "GPS_OK_FIX_3D_RTK_FLOAT": 5,
    "GPS_OK_FIX_3D_RTK_FIXED": 6,
}

# Semantics the docs state, that the emulation follows:
# - "Note that lua ints are 32 bits and lua floats will loose resolution at large values"
#   (docs.lua, uint64_t); ArduPilot builds Lua with LUA_32BITS = 1 (Tools/ardupilotwaf).
INT_BITS = 32
# - "Convert to integer, nil if too large to be represented by native int32" (uint64_t).
# - write_frame's second argument is ``timeout_us``: microseconds.
# - CANFrame:id "The frame ID (11-bit for standard, 29-bit for extended)" with the flags of
#   AP_HAL::CANFrame on top: bit 31 marks an extended frame (FlagEFF, AP_HAL/CANIface.h).
EXTENDED_FLAG = 1 << 31
# - CAN:get_device "buffer_len: buffer length 1 to 25".
BUFFER_LEN = (1, 25)
# - gcs:send_text "The text string to send (max 50 characters)".
GCS_TEXT_MAX = 50
# - param:add_table: table_key 0..200 and num_params 1..63 (bindings.desc).
# - the update function returns itself and the milliseconds until its next run
#   (`return update, UPDATE_INTERVAL_MS` in every driver; mount-djirs2-driver.lua).


def arities(params: tuple[str, ...]) -> set[int]:
    """The argument counts a signature accepts (optional parameters come last)."""
    required = sum(1 for p in params if not p.endswith("?"))
    return set(range(required, len(params) + 1))
