"""The autopilot around a script: its clock, the aircraft, its parameters and what it records."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from analyzer.ardupilot.plan import MountLibrary, step_fields
from analyzer.ardupilot.userdata import ABSOLUTE, Location, ScriptingCANBuffer, Transmit
from analyzer.export.ardupilot_params import AUTOPILOT_PARAMETERS
from analyzer.protocol.types import TOPIC_ARDUPILOT_MOUNT, TOPIC_ARDUPILOT_TARGETS, Event
from analyzer.sim.uav import FlightPath

HOME_ALTITUDE_M = 50.0  # home's altitude above sea level
SOURCE = "ardupilot"

# The parameters an autopilot set up as the driver's page says has (the driver's own are
# added by it), and ArduPilot's defaults of the others the emulation reads.
SETUP_PARAMETERS: dict[str, float] = {
    **{p.name: p.value for p in AUTOPILOT_PARAMETERS},
    "SCR_VM_I_COUNT": 10000,
    "CAN_P2_DRIVER": 0,
    "CAN_D2_PROTOCOL": 0,
}
SCRIPTING_PROTOCOLS = {1: 10, 2: 12}  # get_device: CAN_Dx_PROTOCOL 10, get_device2: 12


@dataclass
class ParamTable:
    key: int
    prefix: str
    size: int
    names: dict[int, str] = field(default_factory=dict)


class Vehicle:
    """What a script on an autopilot talks to: time since boot, the aircraft flying
    ``path``, the mount library's plan, parameters, two scripting CAN drivers (frames
    written go to ``transmit``) and the GCS. ``events`` collects /ardupilot/mount and
    /ardupilot/targets events, timed ``start`` + time since the script started, or by
    ``wall_clock`` when set (a live run: the moment the script reports, not its millis())."""

    def __init__(
        self,
        transmit: Transmit,
        *,
        library: MountLibrary | None = None,
        path: FlightPath | None = None,
        parameters: dict[str, float] | None = None,
        start: float = 0.0,
        boot_ms: int = 0,
        gps_fix: int = 6,  # gps.GPS_OK_FIX_3D_RTK_FIXED
    ) -> None:
        self.transmit = transmit
        self.library = library or MountLibrary()
        self.path = path or FlightPath()
        self.parameters: dict[str, float] = dict(SETUP_PARAMETERS)
        self.parameters.update(parameters or {})
        self.start = start
        self.boot_ms = boot_ms
        self.gps_fix = gps_fix
        self.now_ms = boot_ms
        self.wall_clock: Callable[[], float] | None = None
        self.tables: dict[int, ParamTable] = {}
        self.devices: dict[int, ScriptingCANBuffer] = {}
        self.texts: list[tuple[float, int, str]] = []  # (time, severity, text) to the GCS
        self.mount_reports: list[tuple[float, float, float, float]] = []
        self.events: list[Event] = []
        self.announce(0.0)

    # -- time ------------------------------------------------------------------------------

    @property
    def seconds(self) -> float:
        """Seconds since the script started (``boot_ms`` after the autopilot booted): the
        plan's and the flight's clock."""
        return (self.now_ms - self.boot_ms) / 1000.0

    def event_time(self) -> float:
        if self.wall_clock is not None:
            return self.wall_clock()
        return self.start + self.seconds

    def advance(self, now_ms: int) -> None:
        """Move the clock on; the mount library's new targets become /ardupilot/targets."""
        self.now_ms = now_ms
        self.announce(self.seconds)

    def announce(self, t: float) -> None:
        home = (self.path.home_latitude_deg, self.path.home_longitude_deg)
        for step in self.library.advance(t):
            fields = step_fields(step, home)
            self.events.append(Event(TOPIC_ARDUPILOT_TARGETS, self.event_time(), SOURCE, fields))

    # -- the aircraft ----------------------------------------------------------------------

    def pose(self) -> tuple[Any, float, float]:
        """(UavPose, pitch_deg, roll_deg) now."""
        return self.path.pose(self.seconds)

    def home(self) -> Location:
        return self.location_of(
            self.path.home_latitude_deg, self.path.home_longitude_deg, HOME_ALTITUDE_M
        )

    def location_of(self, lat: float, lon: float, altitude_amsl_m: float) -> Location:
        home_cm = round(HOME_ALTITUDE_M * 100)
        return Location(
            round(lat * 1e7), round(lon * 1e7), round(altitude_amsl_m * 100), ABSOLUTE, home_cm
        )

    def location(self) -> Location:
        pose, _, _ = self.pose()
        return self.location_of(
            pose.latitude_deg, pose.longitude_deg, HOME_ALTITUDE_M + pose.altitude_m
        )

    def attitude_rad(self) -> tuple[float, float, float]:
        """roll, pitch, yaw (0 .. 2 pi) in radians, as the AHRS gives them."""
        pose, pitch, roll = self.pose()
        return math.radians(roll), math.radians(pitch), math.radians(pose.heading_deg % 360.0)

    # -- what the script reports -----------------------------------------------------------

    def report_attitude(self, instance: int, roll: float, pitch: float, yaw: float) -> None:
        self.mount_reports.append((self.event_time(), roll, pitch, yaw))
        fields = {"instance": instance, "roll_deg": roll, "pitch_deg": pitch, "yaw_deg": yaw}
        self.events.append(Event(TOPIC_ARDUPILOT_MOUNT, self.event_time(), SOURCE, fields))

    def send_text(self, severity: int, text: str) -> None:
        self.texts.append((self.event_time(), severity, text))

    def take_events(self) -> list[Event]:
        events, self.events = self.events, []
        return events

    # -- CAN -------------------------------------------------------------------------------

    def can_device(self, driver: int, size: int) -> ScriptingCANBuffer | None:
        """The buffer of scripting CAN driver 1 or 2, if one is configured for it."""
        wanted = SCRIPTING_PROTOCOLS[driver]
        if not any(self.parameters.get(f"CAN_D{d}_PROTOCOL") == wanted for d in (1, 2)):
            return None
        device = ScriptingCANBuffer(driver, size, self.transmit)
        self.devices[driver] = device
        return device

    def deliver(self, can_id: int, data: bytes, extended: bool = True) -> None:
        """A frame on the bus reaches every scripting buffer."""
        for device in self.devices.values():
            device.deliver(can_id, data, extended)
