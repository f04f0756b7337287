"""The picture measurements on the simulated camera's own frames: scale, palette, layout."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pytest

from analyzer.analysis.camera.follow import FeatureCache, follow
from analyzer.analysis.camera.layout import layout_change
from analyzer.analysis.camera.motion import MIN_FEATURES, features, motion
from analyzer.analysis.camera.palette import palette_changed
from analyzer.protocol.command_table import PALETTES
from analyzer.sim.camera.encoder import H264Encoder
from analyzer.sim.camera.frames import MAIN, THERMAL, Gain, Shot, picture
from analyzer.sim.camera.world import make_world
from analyzer.video.decode import decode_window

FPS = 15


@dataclass(frozen=True)
class Unit:
    time: float
    data: bytes


def through_h264(images: list[np.ndarray]) -> list[np.ndarray]:
    """The pictures as a recording holds them: encoded with libx264 and decoded again."""
    height, width = images[0].shape[:2]
    encoder = H264Encoder(width, height, FPS, FPS)
    units = [Unit(i / FPS, d) for i, image in enumerate(images) for d in encoder.encode(image)]
    return [p.rgb for p in decode_window("h264", units, 0.0)]


def shots(count: int, **change: float) -> list[Shot]:
    """A shot every frame, the aircraft flying 12 m/s at 120 m, the gimbal looking 45 deg
    down; ``change`` gives per-second rates (pan deg/s, zoom x/s)."""
    out = []
    for i in range(count):
        t = i / FPS
        out.append(
            Shot(
                12 * t,
                -150.0,
                120.0,
                10.0 + change.get("pan", 0.0) * t,
                -45.0,
                zoom=1.0 + change.get("zoom", 0.0) * t,
                pip_mode=int(change.get("pip", 0)),
            )
        )
    return out


@pytest.mark.slow
@pytest.mark.parametrize("zoom", [1.0, 3.0, 10.0, 30.0])
def test_the_ground_has_texture_at_every_zoom(zoom: float) -> None:
    world = make_world()
    image = picture(world, Shot(0.0, -150.0, 120.0, 10.0, -45.0, zoom=zoom), MAIN, 640, 360)
    assert features(image).count >= MIN_FEATURES * 10


def test_a_zoom_followed_across_frames_is_the_lens_ratio() -> None:
    """Without aircraft motion (it hovers), the lens alone: 1x to 4x in 0.5 s while panning."""
    world = make_world()
    frames = []
    for i in range(9):
        t = i / FPS
        frames.append(Shot(0, -150, 120, 10 + 8 * t, -45, zoom=1 + 6 * t))
    images = through_h264([picture(world, s, MAIN, 640, 360) for s in frames])
    followed = follow(images, FeatureCache(images))
    assert followed.complete
    assert followed.scale == pytest.approx(frames[-1].zoom, rel=0.03)


def test_a_lens_that_stays_keeps_the_scale_while_the_gimbal_turns() -> None:
    world = make_world()
    hovering = [Shot(0.0, -150.0, 120.0, 10.0 + i, -45.0 + i / 2) for i in range(10)]
    images = through_h264([picture(world, s, MAIN, 640, 360) for s in hovering])
    found = motion(features(images[0]), features(images[-1]))
    assert found is not None and found.scale == pytest.approx(1.0, abs=0.01)


@pytest.mark.slow
def test_every_palette_is_told_from_every_other_and_from_itself() -> None:
    """Two frames 1/15 s apart (the gimbal turning 20 deg/s, the aircraft flying 12 m/s):
    another palette always shows, the same one never does."""
    world = make_world()
    names = list(PALETTES.values())
    wrong = []
    for altitude, pitch in ((120.0, -45.0), (40.0, -30.0)):
        first = Shot(0.0, -150.0, altitude, 10.0, pitch)
        second = Shot(0.8, -150.0, altitude, 11.33, pitch - 0.7)
        for one, two in itertools.product(names, names):
            a = picture(world, _with(first, one), THERMAL, 320, 256)
            b = picture(world, _with(second, two), THERMAL, 320, 256)
            if palette_changed(a, b) != (one != two):
                wrong.append((altitude, one, two))
    assert wrong == []


def _with(shot: Shot, palette: str) -> Shot:
    return Shot(shot.east_m, shot.north_m, shot.up_m, shot.yaw_deg, shot.pitch_deg, palette=palette)


@pytest.mark.slow
@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_a_steady_layout_stays_while_the_picture_moves(mode: int) -> None:
    world = make_world()
    gain = Gain()
    images = [picture(world, s, MAIN, 640, 360, gain) for s in shots(12, pan=15, pip=mode)]
    assert layout_change(through_h264(images)) is None


@pytest.mark.parametrize(("old", "new"), [(0, 1), (1, 2), (2, 3), (3, 0)])
def test_each_step_of_pip_cycle_is_seen(old: int, new: int) -> None:
    world = make_world()
    gain = Gain()
    steps = shots(12, pan=15)
    images = []
    for i, shot in enumerate(steps):
        mode = old if i < 6 else new
        moved = Shot(
            shot.east_m, shot.north_m, shot.up_m, shot.yaw_deg, shot.pitch_deg, pip_mode=mode
        )
        images.append(picture(world, moved, MAIN, 640, 360, gain))
    assert layout_change(through_h264(images)) == 6
