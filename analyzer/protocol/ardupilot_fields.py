"""The /ardupilot/mount and /ardupilot/targets event contract: what a mount driver saw."""

from __future__ import annotations

# What the mount library asked for (the ``target`` field of /ardupilot/targets).
TARGET_RATE = "rate"  # mount:get_rate_target
TARGET_ANGLE = "angle"  # mount:get_angle_target
TARGET_LOCATION = "location"  # mount:get_location_target (a point to look at)
TARGET_NONE = "none"  # no target: the pilot let go / the mount library asks nothing
TARGET_CAMERA = "camera"  # a change of camera:get_state
TARGET_KINDS = (TARGET_RATE, TARGET_ANGLE, TARGET_LOCATION, TARGET_NONE, TARGET_CAMERA)

# Camera actions, as camera:get_state shows them changing.
CAMERA_ACTIONS = (
    "take_picture",
    "record_start",
    "record_stop",
    "zoom_rate",
    "zoom_percent",
    "focus_rate",
    "focus_auto",
    "track_point",
    "track_rectangle",
    "track_stop",
)

# name -> (JSON type, description) of the /ardupilot/mount fields (all present).
MOUNT_FIELDS: dict[str, tuple[str, str]] = {
    "instance": ("integer", "mount instance the driver reported (0 = MNT1)"),
    "roll_deg": ("number", "roll the driver reported with mount:set_attitude_euler, degrees"),
    "pitch_deg": ("number", "pitch the driver reported, degrees (positive up)"),
    "yaw_deg": (
        "number",
        "yaw the driver reported, degrees in the body frame (from the aircraft's nose, "
        "positive right)",
    ),
}

# name -> (JSON type, description) of the /ardupilot/targets fields (present as they apply).
TARGET_FIELDS: dict[str, tuple[str, str]] = {
    "target": ("string", "what the mount library (or the camera library) asks for now"),
    "roll_deg": ("number", "angle target: roll, degrees"),
    "pitch_deg": ("number", "angle target: pitch, degrees (positive up)"),
    "yaw_deg": ("number", "angle target: yaw, degrees (earth frame: from north)"),
    "roll_dps": ("number", "rate target: roll rate, deg/s"),
    "pitch_dps": ("number", "rate target: pitch rate, deg/s (positive up)"),
    "yaw_dps": ("number", "rate target: yaw rate, deg/s (positive right)"),
    "yaw_is_earth_frame": (
        "boolean",
        "angle / rate target: the yaw is from north (true) or from the aircraft's nose",
    ),
    "latitude_deg": ("number", "location target: latitude, degrees"),
    "longitude_deg": ("number", "location target: longitude, degrees"),
    "altitude_m": ("number", "location target: altitude above home, metres"),
    "camera_action": ("string", "camera: what changed in camera:get_state"),
    "value": (
        "number",
        "camera: the action's value (zoom / focus rate -1, 0, 1; zoom percent 0..100)",
    ),
    "x": ("number", "camera tracking: point or rectangle's first corner, 0..1 from the left"),
    "y": ("number", "camera tracking: point or rectangle's first corner, 0..1 from the top"),
    "x2": ("number", "camera tracking: rectangle's second corner, 0..1 from the left"),
    "y2": ("number", "camera tracking: rectangle's second corner, 0..1 from the top"),
}
TARGET_ENUMS: dict[str, tuple[str, ...]] = {
    "target": TARGET_KINDS,
    "camera_action": CAMERA_ACTIONS,
}
