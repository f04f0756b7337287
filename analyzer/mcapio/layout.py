"""A ready Foxglove Studio layout for gimbal-analyzer recordings (import it once)."""

from __future__ import annotations

from typing import Any

from analyzer.mcapio.foxglove import TOPIC_DIAGNOSTICS_LOG, TOPIC_TARGET_FIX, TOPIC_UAV_FIX
from analyzer.mcapio.scene_views import TOPIC_SCENE
from analyzer.protocol.types import (
    TOPIC_CAN_BUS_STATE,
    TOPIC_CHECK_STEPS,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
)

# Panel ids are "<panel type>!<name>"; the types are those of Foxglove Studio 1.48.
MAP = "map!gimbal-map"
LOG = "RosOut!gimbal-diagnostics-log"
PLOT = "Plot!gimbal-attitude-and-speeds"
INDICATOR = "Indicator!gimbal-tracking"
STATES = "StateTransitions!gimbal-modes"
RAW = "RawMessages!gimbal-command"
TABLE = "Table!gimbal-diagnostics"
CHECK_STEPS = "Table!check-steps"  # the steps of a bench check (empty in other recordings)
IMAGE = "ImageViewPanel!gimbal-camera"
SCENE = "3D!gimbal-scene"
BUS_PLOT = "Plot!can-bus-state"
# The camera's thumbnails (record --video main): Studio 1.48 draws CompressedImage, not
# CompressedVideo; newer Foxglove can be pointed at /camera/main in the same panel, with
# /camera/main/annotations over it.
CAMERA_THUMBNAIL_TOPIC = "/camera/main/thumbnail"
CAMERA_THUMBNAIL_ANNOTATIONS = "/camera/main/thumbnail/annotations"
# The 3D panel follows the gimbal's position (the world stays upright), seen from behind
# and above, with the frames' axes (/tf) and the scene (aircraft, field of view, target).
SCENE_FOLLOW_FRAME = "gimbal"

# Message paths the layout shows: (topic, field) pairs, checked against the schemas by tests.
PLOT_SERIES = (
    (TOPIC_GIMBAL_ATTITUDE, "pitch_deg"),
    (TOPIC_GIMBAL_ATTITUDE, "yaw_deg"),
    (TOPIC_COMMAND, "pan_speed_dps"),
    (TOPIC_COMMAND, "tilt_speed_dps"),
)
STATE_SERIES = (
    (TOPIC_GIMBAL_ATTITUDE, "control_mode"),
    (TOPIC_GIMBAL_ATTITUDE, "tracking"),
    (TOPIC_COMMAND, "name"),
)
# The CAN controller's state as a number: 0 error-active .. 3 bus-off.
BUS_SERIES = ((TOPIC_CAN_BUS_STATE, "level"),)
TRACKING = (TOPIC_GIMBAL_ATTITUDE, "tracking")

_COLOURS = ("#4e98e2", "#f5774d", "#61cbff", "#f7df71")


def message_path(topic: str, field: str) -> str:
    return f"{topic}.{field}"


def layout() -> dict[str, Any]:
    """The layout as Foxglove Studio exports and imports it (Layouts -> Import layout)."""
    config_by_id: dict[str, Any] = {
        MAP: {
            "layer": "map",
            "zoomLevel": 16,
            "disabledTopics": [],
            "topicColors": {TOPIC_UAV_FIX: "#4e98e2", TOPIC_TARGET_FIX: "#f5774d"},
            "customTileUrl": "",
            "followTopic": TOPIC_UAV_FIX,
        },
        LOG: {"searchTerms": [], "minLogLevel": 1, "topicToRender": TOPIC_DIAGNOSTICS_LOG},
        PLOT: {
            "title": "Plot",
            "paths": [
                {
                    "value": message_path(topic, field),
                    "enabled": True,
                    "timestampMethod": "receiveTime",
                    "color": colour,
                }
                for (topic, field), colour in zip(PLOT_SERIES, _COLOURS, strict=True)
            ],
            "showXAxisLabels": True,
            "showYAxisLabels": True,
            "showLegend": True,
            "legendDisplay": "floating",
            "showPlotValuesInLegend": True,
            "isSynced": True,
            "xAxisVal": "timestamp",
            "sidebarDimension": 240,
        },
        INDICATOR: {
            "path": message_path(*TRACKING),
            "style": "bulb",
            "rules": [
                {"operator": "=", "rawValue": "true", "color": "#68e24a", "label": "tracking"}
            ],
            "fallbackColor": "#a0a0a0",
            "fallbackLabel": "not tracking",
        },
        STATES: {
            "paths": [
                {"value": message_path(topic, field), "timestampMethod": "receiveTime"}
                for topic, field in STATE_SERIES
            ],
            "isSynced": True,
        },
        RAW: {
            "topicPath": TOPIC_COMMAND,
            "diffTopicPath": "",
            "diffMethod": "custom",
            "diffEnabled": False,
            "showFullMessageForDiff": False,
        },
        TABLE: {"topicPath": TOPIC_DIAGNOSTICS},
        CHECK_STEPS: {"topicPath": TOPIC_CHECK_STEPS},
        IMAGE: {
            "cameraTopic": CAMERA_THUMBNAIL_TOPIC,
            "enabledMarkerTopics": [CAMERA_THUMBNAIL_ANNOTATIONS],
            "mode": "fit",
            "pan": {"x": 0, "y": 0},
            "rotation": 0,
            "synchronize": False,
            "transformMarkers": False,
            "zoom": 1,
        },
        SCENE: {
            "cameraState": {
                "distance": 20,
                "perspective": True,
                "phi": 55,
                "target": [0, 0, 0],
                "targetOffset": [0, 0, 0],
                "targetOrientation": [0, 0, 0, 1],
                "thetaOffset": 150,
                "fovy": 45,
                "near": 0.1,
                "far": 5000,
            },
            "followMode": "follow-position",
            "followTf": SCENE_FOLLOW_FRAME,
            "scene": {"transforms": {"showLabel": True, "labelSize": 0.12, "axisScale": 3}},
            "transforms": {},
            "topics": {TOPIC_SCENE: {"visible": True}},
            "layers": {},  # a grid at the world origin is far behind a flying aircraft
        },
    }
    config_by_id[BUS_PLOT] = {
        **config_by_id[PLOT],
        "title": "CAN bus state (0 error-active .. 3 bus-off)",
        "paths": [
            {
                "value": message_path(topic, field),
                "enabled": True,
                "timestampMethod": "receiveTime",
                "color": colour,
            }
            for (topic, field), colour in zip(BUS_SERIES, _COLOURS[3:], strict=False)
        ],
        "minYValue": 0,
        "maxYValue": 3,
    }
    mosaic = {
        "direction": "row",
        "splitPercentage": 50,
        "first": {
            "direction": "column",
            "splitPercentage": 50,
            "first": {
                "direction": "row",
                "splitPercentage": 50,
                "first": IMAGE,
                "second": SCENE,
            },
            "second": {
                "direction": "row",
                "splitPercentage": 50,
                "first": MAP,
                "second": {
                    "direction": "column",
                    "splitPercentage": 30,
                    "first": INDICATOR,
                    "second": LOG,
                },
            },
        },
        "second": {
            "direction": "column",
            "splitPercentage": 40,
            "first": PLOT,
            "second": {
                "direction": "column",
                "splitPercentage": 42,
                "first": {
                    "direction": "row",
                    "splitPercentage": 60,
                    "first": STATES,
                    "second": BUS_PLOT,
                },
                "second": {
                    "direction": "row",
                    "splitPercentage": 50,
                    "first": RAW,
                    "second": {
                        "direction": "column",
                        "splitPercentage": 60,
                        "first": TABLE,
                        "second": CHECK_STEPS,
                    },
                },
            },
        },
    }
    return {
        "configById": config_by_id,
        "globalVariables": {},
        "userNodes": {},
        "linkedGlobalVariables": [],
        "playbackConfig": {"speed": 1},
        "layout": mosaic,
    }
