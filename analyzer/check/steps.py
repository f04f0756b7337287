"""The built-in steps of the bench check: what each sends and what it waits for; no IO."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from analyzer.analysis.samples import MOTOR_YAW, PITCH, YAW
from analyzer.protocol.check_fields import STEP_NAMES
from analyzer.protocol.response_fields import CHECK_PICTURE

REPEAT_S = 0.05  # gimbal_control every 50 ms, as the document recommends (chapter 2.1, 0x04)
IMAGE_CENTRE = 4096  # tracking box centre: the middle of the 0..8191 image coordinates
ZOOM_IN_S = 1.0
ZOOM_BACK_S = 2.5  # zoom_1x: back to 1x and still a while before the gimbal moves on
ZOOM_PITCH = -45.0  # the zoom step looks this far down


@dataclass(frozen=True)
class Attitude:
    """Where the gimbal points: pitch, yaw motor from the nose, and the aircraft's heading
    (the feedback's psi minus the motor's yaw)."""

    pitch: float = 0.0
    motor_yaw: float = 0.0
    heading: float = 0.0


@dataclass(frozen=True)
class Options:
    """What the steps ask for (the check's options)."""

    speed_dps: float = 20.0
    speed_for_s: float = 2.0
    listen_s: float = 3.0
    video: bool = False  # the camera's video is recorded: the zoom is judged from the picture


@dataclass(frozen=True)
class Send:
    """One command; ``goals`` (axis -> angle) are waited for, ``judged`` ones decide the step.

    ``check`` names the /analysis/response check the step waits for (``target``,
    ``tracking``); ``pause`` is a fixed wait after it."""

    name: str
    params: dict[str, Any] = field(default_factory=dict)
    goals: tuple[tuple[str, float], ...] = ()
    judged: bool = False
    check: str = ""
    pause: float = 0.0

    def describe(self) -> str:
        shown = " ".join(
            f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in self.params.items()
        )
        return f"{self.name} {shown}".strip()


@dataclass(frozen=True)
class Hold:
    """gimbal_control at these speeds every 50 ms for ``seconds``, then speeds 0 (judged)."""

    pan_dps: float
    tilt_dps: float
    seconds: float

    @property
    def count(self) -> int:
        return max(1, round(self.seconds / REPEAT_S))


@dataclass(frozen=True)
class Listen:
    """Send nothing; listen to the feedback for ``seconds``."""

    seconds: float


Action = Send | Hold | Listen


@dataclass(frozen=True)
class Plan:
    """A step's actions, the attitude an obedient gimbal ends in, and what is measured."""

    actions: tuple[Action, ...]
    end: Attitude
    axis: str = ""  # the axis whose motion figures are reported
    target: float | None = None
    skipped: str = ""  # why the step cannot be judged from the feedback (zoom)


@dataclass(frozen=True)
class Step:
    name: str
    summary: str
    plan: Callable[[Attitude, Options], Plan]


def _pitch(target: float) -> Send:
    params = {"axis": "pitch", "pitch_deg": target}
    return Send("specified_angle", params, ((PITCH, target),), True, "target")


def _forward(start: Attitude, options: Options) -> Plan:
    # Start from an offset, so that returning to the centre is a move worth measuring.
    pitch, yaw = -45.0, 120.0
    prepare = (
        Send("specified_angle", {"axis": "pitch", "pitch_deg": pitch}, ((PITCH, pitch),)),
        Send(
            "specified_angle",
            {"axis": "yaw", "yaw_deg": yaw, "coordinate_system": "airframe"},
            ((MOTOR_YAW, yaw),),
        ),
    )
    judged = Send("forward", {}, ((PITCH, 0.0), (MOTOR_YAW, 0.0)), True, "target")
    end = Attitude(0.0, 0.0, start.heading)
    return Plan((*prepare, judged), end, MOTOR_YAW, 0.0)


def _pitch_angle(start: Attitude, options: Options) -> Plan:
    target = -90.0 if start.pitch > -45.0 else 0.0
    return Plan((_pitch(target),), Attitude(target, start.motor_yaw, start.heading), PITCH, target)


def _yaw_airframe(start: Attitude, options: Options) -> Plan:
    target = start.motor_yaw + 150.0 if start.motor_yaw <= 20.0 else start.motor_yaw - 150.0
    target = round(target, 1)
    params = {"axis": "yaw", "yaw_deg": target % 360.0, "coordinate_system": "airframe"}
    send = Send("specified_angle", params, ((MOTOR_YAW, target),), True, "target")
    return Plan((send,), Attitude(start.pitch, target, start.heading), MOTOR_YAW, target)


def geodetic_target(start: Attitude) -> tuple[float, float]:
    """(yaw from north to ask for, the motor angle that points there): 120 deg of travel
    from where the motor is, toward the middle of its range, so it can always get there."""
    motor = start.motor_yaw - 120.0 if start.motor_yaw >= -50.0 else start.motor_yaw + 120.0
    motor = round(motor, 1)
    return round((start.heading + motor) % 360.0, 1), motor


def _yaw_geodetic(start: Attitude, options: Options) -> Plan:
    north, motor = geodetic_target(start)
    params = {"axis": "yaw", "yaw_deg": north, "coordinate_system": "geodetic"}
    send = Send("specified_angle", params, ((YAW, north),), True, "target")
    return Plan((send,), Attitude(start.pitch, motor, start.heading), YAW, north)


def _pan_speed(start: Attitude, options: Options) -> Plan:
    speed = -options.speed_dps if start.motor_yaw > 0 else options.speed_dps
    hold = Hold(speed, 0.0, options.speed_for_s)
    end = Attitude(start.pitch, start.motor_yaw + speed * options.speed_for_s, start.heading)
    return Plan((hold,), end, MOTOR_YAW)


def _tilt_speed(start: Attitude, options: Options) -> Plan:
    speed = -options.speed_dps if start.pitch > -25.0 else options.speed_dps
    hold = Hold(0.0, speed, options.speed_for_s)
    end = Attitude(start.pitch + speed * options.speed_for_s, start.motor_yaw, start.heading)
    return Plan((hold,), end, PITCH)


def _look_down(start: Attitude, options: Options) -> Plan:
    actions: tuple[Action, ...] = ()
    if start.pitch < -30.0:  # already looking down: come up first, so the move shows
        actions = (Send("specified_angle", {"axis": "pitch", "pitch_deg": 0.0}, ((PITCH, 0.0),)),)
    judged = Send("look_down", {}, ((PITCH, -90.0),), True, "target")
    return Plan((*actions, judged), Attitude(-90.0, start.motor_yaw, start.heading), PITCH, -90.0)


def _zoom(start: Attitude, options: Options) -> Plan:
    if options.video:  # judged from the picture: zoomed in, then back to 1x
        judged = (
            # the ground (or the bench) in view: texture for the picture's scale, not the sky
            Send(
                "specified_angle",
                {"axis": "pitch", "pitch_deg": ZOOM_PITCH},
                ((PITCH, ZOOM_PITCH),),
            ),
            Send("zoom", {"action": "zoom_in"}, judged=True, check=CHECK_PICTURE, pause=ZOOM_IN_S),
            Send("zoom", {"action": "stop"}, pause=0.2),
            Send(
                "zoom", {"action": "zoom_1x"}, judged=True, check=CHECK_PICTURE, pause=ZOOM_BACK_S
            ),
        )
        return Plan(judged, Attitude(ZOOM_PITCH, start.motor_yaw, start.heading))
    actions = (
        Send("zoom", {"action": "zoom_in"}, pause=ZOOM_IN_S),
        Send("zoom", {"action": "stop"}, pause=0.2),
        Send("zoom", {"action": "zoom_1x"}, pause=0.5),
    )
    why = (
        "the attitude feedback does not report the zoom ratio: record the camera's video "
        "(--video) to judge it from the picture"
    )
    return Plan(actions, start, skipped=why)


def _tracking(start: Attitude, options: Options) -> Plan:
    box = {"x": IMAGE_CENTRE, "y": IMAGE_CENTRE, "width": 512, "height": 512}
    actions = (
        Send("tracking", box, judged=True, check="tracking"),
        Send("tracking_stop", {}, judged=True, check="tracking"),
    )
    return Plan(actions, start)


def _feedback(start: Attitude, options: Options) -> Plan:
    return Plan((Listen(options.listen_s),), start)


STEPS: tuple[Step, ...] = (
    Step("feedback", "listen: feedback period, lost messages, CRC errors", _feedback),
    Step("forward", "from pitch -45 / yaw 120 back to the centre (forward)", _forward),
    Step("pitch_angle", "specified_angle pitch 0 -> -90", _pitch_angle),
    Step("yaw_airframe", "specified_angle yaw 150 deg from the nose (DATA4 = 1)", _yaw_airframe),
    Step("yaw_geodetic", "specified_angle yaw from north, 120 deg of motor travel", _yaw_geodetic),
    Step("pan_speed", "gimbal_control pan at the asked speed every 50 ms, then 0", _pan_speed),
    Step("tilt_speed", "gimbal_control tilt at the asked speed every 50 ms, then 0", _tilt_speed),
    Step("look_down", "look_down: pitch to -90", _look_down),
    Step("zoom", "zoom in, stop, zoom 1x (judged from the video; skipped without)", _zoom),
    Step("tracking", "tracking at the image centre, flag on; tracking_stop, flag off", _tracking),
)
BY_NAME = {step.name: step for step in STEPS}
assert tuple(BY_NAME) == STEP_NAMES


def select(names: str | None) -> tuple[Step, ...]:
    """The steps named in ``a,b,c`` (in the built-in order), all of them for None.

    Raises ValueError naming the unknown ones and the valid names."""
    if names is None:
        return STEPS
    wanted = [n.strip() for n in names.split(",") if n.strip()]
    unknown = [n for n in wanted if n not in BY_NAME]
    if unknown or not wanted:
        what = f"unknown step {', '.join(unknown)}" if unknown else "no step named"
        raise ValueError(f"{what}; the steps are: {', '.join(STEP_NAMES)}")
    return tuple(step for step in STEPS if step.name in wanted)
