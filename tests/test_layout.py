"""The Foxglove layout: valid Foxglove Studio 1.48 layout data whose paths exist in recordings."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from analyzer.cli import main
from analyzer.mcapio.foxglove import VIEW_SCHEMAS, view_schema
from analyzer.mcapio.layout import layout
from analyzer.mcapio.scene_views import TOPIC_SCENE, TOPIC_TF
from analyzer.mcapio.write.video import thumbnail_annotations_topic, thumbnail_topic
from analyzer.protocol.schema import topic_schemas
from analyzer.scene.scene3d import GIMBAL

# Panel types of Foxglove Studio 1.48 (panels/index of @foxglove/studio-base) used here, and
# the config keys each panel reads.
PANEL_KEYS = {
    "map": {"layer", "zoomLevel", "disabledTopics", "topicColors", "customTileUrl", "followTopic"},
    "RosOut": {"searchTerms", "minLogLevel", "topicToRender"},
    "Plot": {"paths", "isSynced", "xAxisVal", "showLegend"},
    "Indicator": {"path", "style", "rules", "fallbackColor", "fallbackLabel"},
    "StateTransitions": {"paths", "isSynced"},
    "RawMessages": {"topicPath", "diffTopicPath", "diffMethod", "diffEnabled"},
    "Table": {"topicPath"},
    "ImageViewPanel": {"cameraTopic", "enabledMarkerTopics", "mode", "synchronize"},
    "3D": {"cameraState", "followMode", "followTf", "scene", "topics", "layers"},
}


def leaves(node: Any) -> list[str]:
    if isinstance(node, str):
        return [node]
    assert set(node) == {"direction", "splitPercentage", "first", "second"}, node
    assert node["direction"] in ("row", "column") and 0 < node["splitPercentage"] < 100
    return leaves(node["first"]) + leaves(node["second"])


def field_exists(path: str) -> bool:
    """'/gimbal/attitude.pitch_deg' names a property of that topic's schema."""
    topic, _, field = path.partition(".")
    schemas = {**topic_schemas(), **{t: s for t, (_, s) in VIEW_SCHEMAS.items()}}
    return topic in schemas and (not field or field in schemas[topic]["properties"])


def test_layout_is_foxglove_layout_data() -> None:
    data = json.loads(json.dumps(layout()))
    assert set(data) == {
        "configById",
        "globalVariables",
        "userNodes",
        "linkedGlobalVariables",
        "playbackConfig",
        "layout",
    }
    panels = leaves(data["layout"])
    assert sorted(panels) == sorted(data["configById"])
    assert len(set(panels)) == len(panels)
    for panel_id, config in data["configById"].items():
        kind, _, name = panel_id.partition("!")
        assert name and kind in PANEL_KEYS, panel_id
        assert PANEL_KEYS[kind] <= set(config), (panel_id, PANEL_KEYS[kind] - set(config))
    assert {p.partition("!")[0] for p in panels} == set(PANEL_KEYS)  # every panel the issue names


def test_every_message_path_exists_in_the_schemas() -> None:
    config = layout()["configById"]
    paths: list[str] = []
    for panel_id, panel in config.items():
        kind = panel_id.partition("!")[0]
        if kind in ("Plot", "StateTransitions"):
            paths += [p["value"] for p in panel["paths"]]
        elif kind == "Indicator":
            paths.append(panel["path"])
        elif kind in ("RawMessages", "Table"):
            paths.append(panel["topicPath"])
        elif kind == "RosOut":
            paths.append(panel["topicToRender"])
        elif kind == "map":
            paths += [*panel["topicColors"], panel["followTopic"]]
    assert "/gimbal/command.pan_speed_dps" in paths and "/gimbal/attitude.pitch_deg" in paths
    assert "/gimbal/attitude.control_mode" in paths and "/gimbal/attitude.tracking" in paths
    for path in paths:
        assert field_exists(path), path


def test_the_camera_and_3d_panels_show_the_overlays_and_the_scene() -> None:
    config = layout()["configById"]
    image = config["ImageViewPanel!gimbal-camera"]
    assert image["cameraTopic"] == thumbnail_topic("main")
    assert image["enabledMarkerTopics"] == [thumbnail_annotations_topic("main")]
    assert view_schema(thumbnail_annotations_topic("main"))[0] == "foxglove.ImageAnnotations"
    scene = config["3D!gimbal-scene"]
    assert scene["followTf"] == GIMBAL and scene["followMode"] == "follow-position"
    assert scene["topics"] == {TOPIC_SCENE: {"visible": True}}  # scene entities start hidden
    assert VIEW_SCHEMAS[TOPIC_SCENE][0] == "foxglove.SceneUpdate"
    assert VIEW_SCHEMAS[TOPIC_TF][0] == "foxglove.FrameTransforms"


def test_layout_command_writes_and_refuses_to_overwrite(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["layout"]) == 0
    written = tmp_path / "gimbal-layout.json"
    assert json.loads(written.read_text(encoding="utf-8")) == json.loads(json.dumps(layout()))
    assert "Import layout" in capsys.readouterr().err
    written.write_text("mine", encoding="utf-8")
    assert main(["layout"]) == 2
    assert "exists; choose another name or use --force" in capsys.readouterr().err
    assert written.read_text(encoding="utf-8") == "mine"
    assert main(["layout", "--force"]) == 0
    assert json.loads(written.read_text(encoding="utf-8"))["configById"]
    capsys.readouterr()
    assert main(["layout", "-o", "-"]) == 0
    assert json.loads(capsys.readouterr().out) == json.loads(written.read_text(encoding="utf-8"))
    assert main(["layout", "-o", str(tmp_path / "missing" / "x.json")]) == 2
    assert list(tmp_path.iterdir()) == [written]  # no temporary file left behind
