"""The built-in steps of the bench check: what each sends and what it waits for; no IO."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from analyzer.analysis.samples import MOTOR_YAW, MOTOR_YAW_LIMITS, PITCH, PITCH_LIMITS, YAW
from analyzer.check.align import Goals
from analyzer.protocol.check_fields import STEP_NAMES
from analyzer.protocol.response_fields import CHECK_PICTURE

REPEAT_S = 0.05  # gimbal_control every 50 ms, as the document recommends (chapter 2.1, 0x04)
IMAGE_CENTRE = 4096  # tracking box centre: the middle of the 0..8191 image coordinates
ZOOM_IN_S = 1.0
ZOOM_BACK_S = 2.5  # zoom_1x: back to 1x and still a while before the gimbal moves on
ZOOM_PITCH = -45.0  # the zoom step looks this far down
MIXED_UP_REACH = 160.0  # a yaw target read in the wrong frame stays this far from the back
GEODETIC_TURN = 150.0  # the yaw_geodetic step's turn of the motor


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
    """A step's actions, the attitude an obedient gimbal ends in, and what is measured.

    ``start``: the attitude (of the axes it names) the gimbal is brought to before the
    first action, whatever attitude it was in (``analyzer.check.align``)."""

    actions: tuple[Action, ...]
    end: Attitude
    axis: str = ""  # the axis whose motion figures are reported
    target: float | None = None
    skipped: str = ""  # why the step cannot be judged from the feedback (zoom)
    start: Goals = ()


@dataclass(frozen=True)
class CheckStep:
    name: str
    summary: str
    plan: Callable[[Attitude, Options], Plan]


def _pitch(target: float) -> Send:
    params = {"axis": "pitch", "pitch_deg": target}
    return Send("specified_angle", params, ((PITCH, target),), True, "target")


# Where the steps start. Every step names the attitude (of the axes it moves) it starts
# from, and the gimbal is brought there first: a step does the same from wherever the
# gimbal was left.
FORWARD_FROM: Goals = ((PITCH, -45.0), (MOTOR_YAW, 150.0))  # off centre: a move to measure
# Moves of 135 deg and more: at 60 deg/s they pass four feedback messages on their way,
# so the slew is measured even when one of them is lost and another is a ranging one.
LOOKING_UP: Goals = ((PITCH, 45.0),)
NOSE: Goals = ((MOTOR_YAW, 0.0),)


def _forward(now: Attitude, options: Options) -> Plan:
    judged = Send("forward", {}, ((PITCH, 0.0), (MOTOR_YAW, 0.0)), True, "target")
    end = Attitude(0.0, 0.0, now.heading)
    return Plan((judged,), end, MOTOR_YAW, 0.0, start=FORWARD_FROM)


def _pitch_angle(now: Attitude, options: Options) -> Plan:
    target = -90.0
    end = Attitude(target, now.motor_yaw, now.heading)
    return Plan((_pitch(target),), end, PITCH, target, start=LOOKING_UP)


def _yaw_airframe(now: Attitude, options: Options) -> Plan:
    target = 150.0
    params = {"axis": "yaw", "yaw_deg": target, "coordinate_system": "airframe"}
    send = Send("specified_angle", params, ((MOTOR_YAW, target),), True, "target")
    return Plan((send,), Attitude(now.pitch, target, now.heading), MOTOR_YAW, target, start=NOSE)


def geodetic_target(start: Attitude) -> tuple[float, float]:
    """(yaw from north to ask for, the motor angle that points there): 150 deg of travel
    from where the motor is, toward the middle of its range, so it can always get there.
    From the nose, either way: the one whose angle from north, taken as an angle from the
    nose (DATA4 mixed up), the motor could reach too, so that such a mix-up shows."""
    ways = [-GEODETIC_TURN, GEODETIC_TURN]
    if start.motor_yaw < -20.0:
        ways.reverse()
    if abs(start.motor_yaw) < 20.0:  # at the nose: either way stays in the range
        for way in ways:
            north = (start.heading + start.motor_yaw + way) % 360.0
            if abs((north + 180.0) % 360.0 - 180.0) <= MIXED_UP_REACH:
                ways = [way]
                break
    motor = round(start.motor_yaw + ways[0], 1)
    return round((start.heading + motor) % 360.0, 1), motor


def _yaw_geodetic(now: Attitude, options: Options) -> Plan:
    north, motor = geodetic_target(Attitude(now.pitch, 0.0, now.heading))
    params = {"axis": "yaw", "yaw_deg": north, "coordinate_system": "geodetic"}
    send = Send("specified_angle", params, ((YAW, north),), True, "target")
    return Plan((send,), Attitude(now.pitch, motor, now.heading), YAW, north, start=NOSE)


def speed_start(speed: float, seconds: float, low: float, high: float) -> float:
    """Where a speed step starts on an axis of range low..high: the turn it asks for
    (``speed`` deg/s for ``seconds``) is centred in the range."""
    middle = (low + high) / 2 - speed * seconds / 2
    return round(min(high, max(low, middle)), 1)


def _pan_speed(now: Attitude, options: Options) -> Plan:
    speed = options.speed_dps  # to the right, from left of the nose
    yaw = speed_start(speed, options.speed_for_s, -MOTOR_YAW_LIMITS, MOTOR_YAW_LIMITS)
    hold = Hold(speed, 0.0, options.speed_for_s)
    end = Attitude(now.pitch, yaw + speed * options.speed_for_s, now.heading)
    return Plan((hold,), end, MOTOR_YAW, start=((MOTOR_YAW, yaw),))


def _tilt_speed(now: Attitude, options: Options) -> Plan:
    speed = -options.speed_dps  # downward, from above the middle of the range
    pitch = speed_start(speed, options.speed_for_s, *PITCH_LIMITS)
    hold = Hold(0.0, speed, options.speed_for_s)
    end = Attitude(pitch + speed * options.speed_for_s, now.motor_yaw, now.heading)
    return Plan((hold,), end, PITCH, start=((PITCH, pitch),))


def _look_down(now: Attitude, options: Options) -> Plan:
    judged = Send("look_down", {}, ((PITCH, -90.0),), True, "target")
    end = Attitude(-90.0, now.motor_yaw, now.heading)
    return Plan((judged,), end, PITCH, -90.0, start=LOOKING_UP)


def _zoom(now: Attitude, options: Options) -> Plan:
    if options.video:  # judged from the picture: zoomed in, then back to 1x
        judged = (
            Send("zoom", {"action": "zoom_in"}, judged=True, check=CHECK_PICTURE, pause=ZOOM_IN_S),
            Send("zoom", {"action": "stop"}, pause=0.2),
            Send(
                "zoom", {"action": "zoom_1x"}, judged=True, check=CHECK_PICTURE, pause=ZOOM_BACK_S
            ),
        )
        # the ground (or the bench) in view: texture for the picture's scale, not the sky
        end = Attitude(ZOOM_PITCH, now.motor_yaw, now.heading)
        return Plan(judged, end, start=((PITCH, ZOOM_PITCH),))
    actions = (
        Send("zoom", {"action": "zoom_in"}, pause=ZOOM_IN_S),
        Send("zoom", {"action": "stop"}, pause=0.2),
        Send("zoom", {"action": "zoom_1x"}, pause=0.5),
    )
    why = (
        "the attitude feedback does not report the zoom ratio: record the camera's video "
        "(--video) to judge it from the picture"
    )
    return Plan(actions, now, skipped=why)


def _tracking(now: Attitude, options: Options) -> Plan:
    box = {"x": IMAGE_CENTRE, "y": IMAGE_CENTRE, "width": 512, "height": 512}
    actions = (
        Send("tracking", box, judged=True, check="tracking"),
        Send("tracking_stop", {}, judged=True, check="tracking"),
    )
    return Plan(actions, now)


def _feedback(now: Attitude, options: Options) -> Plan:
    return Plan((Listen(options.listen_s),), now)


STEPS: tuple[CheckStep, ...] = (
    CheckStep("feedback", "listen: feedback period, lost messages, CRC errors", _feedback),
    CheckStep("forward", "from pitch -45 / yaw motor 150 back to the centre (forward)", _forward),
    CheckStep("pitch_angle", "specified_angle pitch 45 -> -90", _pitch_angle),
    CheckStep(
        "yaw_airframe",
        "specified_angle yaw motor 0 -> 150 from the nose (DATA4 = 1)",
        _yaw_airframe,
    ),
    CheckStep(
        "yaw_geodetic", "specified_angle yaw from north: yaw motor 0 -> +-150", _yaw_geodetic
    ),
    CheckStep("pan_speed", "gimbal_control pan at the asked speed every 50 ms, then 0", _pan_speed),
    CheckStep(
        "tilt_speed", "gimbal_control tilt at the asked speed every 50 ms, then 0", _tilt_speed
    ),
    CheckStep("look_down", "look_down: pitch 45 -> -90", _look_down),
    CheckStep("zoom", "zoom in, stop, zoom 1x (judged from the video; skipped without)", _zoom),
    CheckStep(
        "tracking", "tracking at the image centre, flag on; tracking_stop, flag off", _tracking
    ),
)
BY_NAME = {step.name: step for step in STEPS}
assert tuple(BY_NAME) == STEP_NAMES


def select(names: str | None) -> tuple[CheckStep, ...]:
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
