"""What the simulated camera sees of the simulation: the gimbal's attitude, zoom and modes."""

from __future__ import annotations

import copy
import math
import threading
from typing import TYPE_CHECKING

from analyzer.sim.engine import SimulatedGimbal
from analyzer.sim.model import EARTH_M_PER_DEG, GimbalModel, UavPose
from analyzer.sim.uav import FlightPath

if TYPE_CHECKING:  # the pictures (OpenCV) only when a stream is asked for
    from analyzer.sim.camera.frames import Shot

HOME = FlightPath()  # the world's origin is the orbit's centre


def local_metres(latitude_deg: float, longitude_deg: float) -> tuple[float, float]:
    """(east, north) metres of a position from home (the flat earth of ``offset_position``)."""
    north = (latitude_deg - HOME.home_latitude_deg) * EARTH_M_PER_DEG
    scale = EARTH_M_PER_DEG * max(0.01, math.cos(math.radians(latitude_deg)))
    return (longitude_deg - HOME.home_longitude_deg) * scale, north


def shot_of(model: GimbalModel, pose: UavPose) -> Shot:
    """The camera's shot for a gimbal model hanging under an aircraft at ``pose``."""
    from analyzer.sim.camera.frames import Shot

    east, north = local_metres(pose.latitude_deg, pose.longitude_deg)
    box = model.tracking_box if model.tracking else (0.0, 0.0)
    return Shot(
        east,
        north,
        pose.altitude_m,
        (pose.heading_deg + model.motor_yaw_deg) % 360.0,
        model.pitch_deg,
        model.zoom,
        model.digital_zoom,
        model.palette,
        model.pip_mode,
        box,
    )


class GimbalEye:
    """The simulated gimbal as the camera sees it, from the camera's own thread.

    ``attach`` the gimbal once it exists; ``shot(now)`` (monotonic seconds, the
    simulation's clock) looks at a copy of its model advanced to ``now``, so the picture
    shows the zoom and the angles of that very moment and the simulation is left alone."""

    def __init__(self) -> None:
        self._gimbal: SimulatedGimbal | None = None
        self.attached = threading.Event()

    def attach(self, gimbal: SimulatedGimbal) -> None:
        self._gimbal = gimbal
        self.attached.set()

    def shot(self, now: float) -> Shot | None:
        gimbal = self._gimbal
        if gimbal is None:
            return None
        model = copy.copy(gimbal.model)
        if gimbal.uav is not None:
            model.uav = gimbal.uav.pose(now)
        model.step(now)
        return shot_of(model, model.uav)
