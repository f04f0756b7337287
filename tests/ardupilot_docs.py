"""ArduPilot's scripting API as its docs.lua declares it: the facts the emulation is held to.

Source: ArduPilot's libraries/AP_Scripting/docs/docs.lua, master, in its annotated revision
(the one declaring ``CAN:get_device2``, ``CANFrame_ud:id_signed``, ``camera:get_state`` and
``mount:get_rate_target``); the same signatures are in the file docs.lua is generated from,
libraries/AP_Scripting/generator/description/bindings.desc at ArduPilot commit
002c901c0fd26cdeed6e8a32dd52988b8489ceed, and ``ScriptingCANBuffer_ud:write_frame(frame,
timeout_us)`` already in docs.lua at commit 85503302031cfab761551f4da5180b6b3c524ad6.
"""

from __future__ import annotations

DOCS_VERSION = (
    "docs.lua (ArduPilot master, annotated revision) / bindings.desc @ 002c901c0fd2 / "
    "docs.lua @ 85503302031c"
)

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
