"""The 3D panel's messages: ``foxglove.FrameTransforms`` of world, aircraft, gimbal and camera,
and a ``foxglove.SceneUpdate`` with the aircraft, the field of view and the ranging target."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from analyzer.scene.geometry import (
    IDENTITY,
    OPTICAL,
    Quaternion,
    Vector,
    aircraft_rotation,
    gimbal_rotation,
)
from analyzer.scene.state import GimbalState

WORLD = "world"  # east/north/up metres from the aircraft's first fix
AIRCRAFT = "uav"  # the aircraft's body: x forward, y left, z up
BASE = "base"  # the fixed mount the gimbal hangs under when no UAV status came
GIMBAL = "gimbal"  # x along the line of sight
GIMBAL_DROP_M = 0.6  # the gimbal hangs this far under the aircraft's centre
HFOV_1X_DEG = 60.0  # horizontal field of view at 1x of the 30x / 35x zoom cameras
DEFAULT_ASPECT = 16 / 9
FRUSTUM_M = 8.0  # length of the field of view's lines when no ranging says how far
MAX_FRUSTUM_M = 200.0

# SceneEntityDeletionType, LineType
MATCHING_ID = 0
LINE_LIST = 2
ENTITY_AIRCRAFT = "aircraft"
ENTITY_FOV = "field_of_view"
ENTITY_TARGET = "ranging_target"


def optical_frame(camera: str) -> str:
    """The optical frame of a camera stream (its pictures' ``frame_id``)."""
    return f"camera_{camera}"


def _translation(at: Vector) -> dict[str, float]:
    return {"x": round(at.x, 3), "y": round(at.y, 3), "z": round(at.z, 3)}


def _rotation(q: Quaternion) -> dict[str, float]:
    return {"x": round(q.x, 7), "y": round(q.y, 7), "z": round(q.z, 7), "w": round(q.w, 7)}


# The parts that never change, made once (every feedback sends them; nobody edits them).
_AT_ORIGIN = _translation(Vector(0.0, 0.0, 0.0))
_UNDER_MOUNT = _translation(Vector(0.0, 0.0, -GIMBAL_DROP_M))
_NOT_TURNED = _rotation(IDENTITY)
_TO_OPTICAL = _rotation(OPTICAL)


def _transform(
    stamp: dict[str, int],
    parent: str,
    child: str,
    rotation: dict[str, float],
    translation: dict[str, float],
) -> dict[str, Any]:
    return {
        "timestamp": stamp,
        "parent_frame_id": parent,
        "child_frame_id": child,
        "translation": translation,
        "rotation": rotation,
    }


def frame_transforms(
    state: GimbalState, stamp: dict[str, int], optical_frames: Sequence[str]
) -> dict[str, Any] | None:
    """The ``foxglove.FrameTransforms`` of the moment (None before the gimbal's first feedback):
    world -> aircraft (or world -> base without UAV status) -> gimbal -> optical frames."""
    if state.pitch_deg is None or state.motor_yaw_deg is None:
        return None
    if state.aircraft is not None:
        heading, pitch, roll = state.aircraft
        mount = AIRCRAFT
        body = _rotation(aircraft_rotation(heading, pitch, roll))
        first = _transform(stamp, WORLD, AIRCRAFT, body, _translation(Vector(*state.position)))
    else:
        mount = BASE
        first = _transform(stamp, WORLD, BASE, _NOT_TURNED, _AT_ORIGIN)
    gimbal = _rotation(gimbal_rotation(state.motor_yaw_deg, state.pitch_deg))
    transforms = [first, _transform(stamp, mount, GIMBAL, gimbal, _UNDER_MOUNT)]
    transforms.extend(_transform(stamp, GIMBAL, f, _TO_OPTICAL, _AT_ORIGIN) for f in optical_frames)
    return {"transforms": transforms}


def field_of_view(zoom: float | None, aspect: float = DEFAULT_ASPECT) -> tuple[float, float]:
    """Horizontal and vertical field of view (degrees) at a zoom ratio (1x when unknown)."""
    half = math.tan(math.radians(HFOV_1X_DEG) / 2) / max(1.0, zoom or 1.0)
    return math.degrees(2 * math.atan(half)), math.degrees(2 * math.atan(half / aspect))


def _pose(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> dict[str, Any]:
    return {
        "position": {"x": x, "y": y, "z": z},
        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
    }


def _colour(r: float, g: float, b: float, a: float = 1.0) -> dict[str, float]:
    return {"r": r, "g": g, "b": b, "a": a}


def _entity(stamp: dict[str, int], frame: str, name: str, **shapes: Any) -> dict[str, Any]:
    """A ``foxglove.SceneEntity`` with every field given (Studio 1.48 expects them all)."""
    entity: dict[str, Any] = {
        "timestamp": stamp,
        "frame_id": frame,
        "id": name,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": True,
        "metadata": [],
    }
    for kind in ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts"):
        entity[kind] = shapes.get(kind, [])
    entity["models"] = []
    return entity


def _text(text: str, at: dict[str, Any], size: float = 14.0) -> dict[str, Any]:
    return {
        "pose": at,
        "billboard": True,
        "font_size": size,
        "scale_invariant": True,
        "color": _colour(1.0, 1.0, 1.0),
        "text": text,
    }


def _aircraft(stamp: dict[str, int], state: GimbalState) -> dict[str, Any]:
    frame = AIRCRAFT if state.aircraft is not None else BASE
    body = {
        "pose": _pose(),
        "size": {"x": 2.0, "y": 2.0, "z": 0.25},
        "color": _colour(0.6, 0.6, 0.65, 0.6),
    }
    nose = {
        "pose": _pose(),
        "shaft_length": 1.6,
        "shaft_diameter": 0.12,
        "head_length": 0.5,
        "head_diameter": 0.3,
        "color": _colour(0.95, 0.45, 0.3),
    }
    label = "aircraft" if state.aircraft is not None else "gimbal mount (no UAV status)"
    texts = [_text(label, _pose(0.0, 0.0, 0.8), 12.0)]
    return _entity(stamp, frame, ENTITY_AIRCRAFT, cubes=[body], arrows=[nose], texts=texts)


def _frustum(stamp: dict[str, int], state: GimbalState, aspect: float) -> dict[str, Any]:
    depth = min(state.range_m or FRUSTUM_M, MAX_FRUSTUM_M)
    hfov, vfov = field_of_view(state.zoom, aspect)
    dy = depth * math.tan(math.radians(hfov) / 2)
    dz = depth * math.tan(math.radians(vfov) / 2)
    depth, dy, dz = round(depth, 3), round(dy, 3), round(dz, 3)  # millimetres are plenty
    corners = [(depth, dy, dz), (depth, -dy, dz), (depth, -dy, -dz), (depth, dy, -dz)]
    points: list[dict[str, float]] = []
    for i, corner in enumerate(corners):
        following = corners[(i + 1) % 4]
        points += [{"x": 0.0, "y": 0.0, "z": 0.0}, dict(zip("xyz", corner, strict=True))]
        points += [dict(zip("xyz", corner, strict=True)), dict(zip("xyz", following, strict=True))]
    line = {
        "type": LINE_LIST,
        "pose": _pose(),
        "thickness": 2.0,
        "scale_invariant": True,
        "points": points,
        "color": _colour(1.0, 0.85, 0.2),
        "colors": [],
        "indices": [],
    }
    zoom = "zoom ?" if state.zoom is None else f"{state.zoom:.1f}x"
    label = _text(f"{zoom}  {hfov:.1f} x {vfov:.1f} deg", _pose(depth, 0.0, dz), 12.0)
    return _entity(stamp, GIMBAL, ENTITY_FOV, lines=[line], texts=[label])


def _target(stamp: dict[str, int], distance: float) -> dict[str, Any]:
    size = max(0.4, distance * 0.02)
    sphere = {
        "pose": _pose(distance),
        "size": {"x": size, "y": size, "z": size},
        "color": _colour(0.96, 0.47, 0.3, 0.9),
    }
    label = _text(f"laser {distance:.1f} m", _pose(distance, 0.0, size))
    return _entity(stamp, GIMBAL, ENTITY_TARGET, spheres=[sphere], texts=[label])


def scene_update(
    state: GimbalState, stamp: dict[str, int], aspect: float = DEFAULT_ASPECT
) -> dict[str, Any]:
    """The whole scene in one ``foxglove.SceneUpdate`` (a seek shows it from one message):
    the aircraft (or the fixed mount), the field of view along the gimbal's x axis, drawn
    as far as the laser range, and the ranging target when the last ranging succeeded."""
    entities = [_aircraft(stamp, state), _frustum(stamp, state, aspect)]
    deletions = []
    if state.range_m is not None:
        entities.append(_target(stamp, state.range_m))
    else:
        deletions.append({"timestamp": stamp, "type": MATCHING_ID, "id": ENTITY_TARGET})
    return {"deletions": deletions, "entities": entities}
