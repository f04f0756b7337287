"""Foxglove views of where the gimbal points: /tf, the 3D scene and the camera overlays."""

from __future__ import annotations

import json
from importlib import resources
from typing import Any

from analyzer.mcapio.log_time import timestamp
from analyzer.protocol.types import Event
from analyzer.scene.overlays import image_annotations, overlay
from analyzer.scene.scene3d import DEFAULT_ASPECT, frame_transforms, optical_frame, scene_update
from analyzer.scene.state import COMMAND, FEEDBACK, INPUT_TOPICS, RANGING, GimbalState

TOPIC_TF = "/tf"  # the frames: world -> uav (or base) -> gimbal -> camera_NAME
TOPIC_SCENE = "/gimbal/scene"  # aircraft, field of view and laser target for the 3D panel

FRAME_TRANSFORMS = "foxglove.FrameTransforms"
SCENE_UPDATE = "foxglove.SceneUpdate"
IMAGE_ANNOTATIONS = "foxglove.ImageAnnotations"
ANNOTATIONS_SUFFIX = "/annotations"
SCENE_EVERY_S = 1.0  # the scene is sent again at least this often (with feedback)
DEFAULT_CAMERA_FRAME = optical_frame("main")  # before any stream is known


def foxglove_schema(title: str) -> dict[str, Any]:
    """Foxglove's own JSON Schema of ``title`` (foxglove/schemas, schemas/jsonschema), as shipped
    in analyzer/mcapio/foxglove_schemas."""
    name = title.removeprefix("foxglove.") + ".json"
    folder = resources.files("analyzer.mcapio").joinpath("foxglove_schemas")
    text = folder.joinpath(name).read_text(encoding="utf-8")
    schema: dict[str, Any] = json.loads(text)
    return schema


SCENE_SCHEMAS: dict[str, tuple[str, dict[str, Any]]] = {
    TOPIC_TF: (FRAME_TRANSFORMS, foxglove_schema(FRAME_TRANSFORMS)),
    TOPIC_SCENE: (SCENE_UPDATE, foxglove_schema(SCENE_UPDATE)),
}
ANNOTATIONS_SCHEMA = (IMAGE_ANNOTATIONS, foxglove_schema(IMAGE_ANNOTATIONS))


def is_annotation_topic(topic: str) -> bool:
    return topic.endswith(ANNOTATIONS_SUFFIX)


class SceneViews:
    """Follows the gimbal (``analyzer.scene.state``) and gives, at the time of each event,
    the messages it calls for: with every feedback the transforms and the overlays, with a
    tracking, tap or zoom command the overlays, and with any of them or a ranging the scene
    when it changed shape or once ``SCENE_EVERY_S`` has passed.

    The camera streams are told by ``add_camera`` (their optical frames hang under the
    gimbal) and ``add_overlay`` (a topic to draw the overlays on, with its picture size)."""

    def __init__(self) -> None:
        self.state = GimbalState()
        self.optical_frames: list[str] = []
        self.overlays: dict[str, tuple[int, int, bool]] = {}
        self.aspect = DEFAULT_ASPECT
        self._scene_at: float | None = None
        self._scene_key: tuple[Any, ...] = ()

    def add_camera(self, name: str) -> None:
        frame = optical_frame(name)
        if frame not in self.optical_frames:
            self.optical_frames.append(frame)

    def add_overlay(self, topic: str, width: int, height: int, *, stroked: bool = False) -> None:
        """Draw on ``topic`` for a ``width`` x ``height`` picture; ``stroked``: the text line
        as line segments (``analyzer.scene.overlays.image_annotations``)."""
        if width > 0 and height > 0:
            if not self.overlays:
                self.aspect = width / height
            self.overlays[topic] = (width, height, stroked)

    def views(self, event: Event) -> list[tuple[str, dict[str, Any]]]:
        if event.topic not in INPUT_TOPICS:
            return []
        change = self.state.observe(event)
        out: list[tuple[str, dict[str, Any]]] = []
        if change == FEEDBACK:
            stamp = timestamp(event.time)
            transforms = frame_transforms(
                self.state, stamp, self.optical_frames or [DEFAULT_CAMERA_FRAME]
            )
            if transforms is not None:
                out.append((TOPIC_TF, transforms))
        if change in (FEEDBACK, COMMAND, RANGING):
            out.extend(self._scene(event.time))
        if change in (FEEDBACK, COMMAND) and self.overlays:
            stamp = timestamp(event.time)
            shapes = overlay(self.state)
            for topic, (width, height, stroked) in self.overlays.items():
                message = image_annotations(shapes, width, height, stamp, stroked=stroked)
                out.append((topic, message))
        return out

    def _scene(self, time: float) -> list[tuple[str, dict[str, Any]]]:
        """The scene when its shape changed (zoom, a target found or lost, UAV status), else
        at most every ``SCENE_EVERY_S`` (a new laser range, a viewer that joined late)."""
        state = self.state
        if state.pitch_deg is None:  # nothing to hang the scene on before the first feedback
            return []
        key = (state.zoom, state.range_m is None, state.aircraft is not None, self.aspect)
        due = self._scene_at is None or time - self._scene_at >= SCENE_EVERY_S
        if not (due or key != self._scene_key):
            return []
        self._scene_at, self._scene_key = time, key
        return [(TOPIC_SCENE, scene_update(state, timestamp(time), self.aspect))]
