"""`check --dry-run`: the frames the steps would send, with their latest times; nothing is sent."""

from __future__ import annotations

from analyzer.analysis.samples import MOTOR_YAW, PITCH, YAW
from analyzer.check.align import CENTRING, Goals, commands_for
from analyzer.check.runner import AFTER_DEADLINE_S, encode
from analyzer.check.steps import REPEAT_S, Attitude, CheckStep, Hold, Listen, Options, Send
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.ids import CONTROL_ID
from analyzer.protocol.types import hexstr


def _line(at: float, step: str, what: str, data: bytes, extra: str = "") -> str:
    return (
        f"  +{at:6.2f} s  {step:<13} {what:<52} {CONTROL_ID:08X}#{data.hex().upper()}  "
        f"TCP {hexstr(wrap_control(data))}{extra}"
    )


def _turn(goals: Goals, attitude: Attitude) -> float:
    """The largest turn (deg) from ``attitude`` to a step's start."""
    values = {PITCH: attitude.pitch, MOTOR_YAW: attitude.motor_yaw}
    values[YAW] = attitude.heading + attitude.motor_yaw
    return max((abs(values[axis] - angle) for axis, angle in goals), default=0.0)


def dry_run_lines(
    steps: tuple[CheckStep, ...], options: Options, allowed_s: float, min_slew_dps: float
) -> list[str]:
    """Every frame of ``steps`` (and the final centring) for a gimbal that starts centred.

    A step first brings the gimbal to its start when it is not there (waiting at most
    the turn at ``min_slew_dps`` and the time allowed), then waits for it to settle, at
    most the time allowed: the times shown are the latest each frame would go."""
    lines: list[str] = []
    at = 0.0
    attitude = Attitude()
    wait = allowed_s + AFTER_DEADLINE_S
    for step in steps:
        plan = step.plan(attitude, options)
        turn = _turn(plan.start, attitude)
        if turn > 1e-6:
            for name, params in commands_for(plan.start):
                what, data = Send(name, params).describe(), encode(name, params)
                lines.append(_line(at, step.name, what, data, "  (the step's start)"))
            at += turn / min_slew_dps + allowed_s
        for action in plan.actions:
            if isinstance(action, Listen):
                lines.append(
                    f"  +{at:6.2f} s  {step.name:<13} listen {action.seconds:g} s (send nothing)"
                )
                at += action.seconds
            elif isinstance(action, Hold):
                params = {"pan_speed_dps": action.pan_dps, "tilt_speed_dps": action.tilt_dps}
                what = Send("gimbal_control", params).describe()
                every = f"  x{action.count} every {REPEAT_S * 1000:g} ms"
                lines.append(_line(at, step.name, what, encode("gimbal_control", params), every))
                at += action.count * REPEAT_S
                stop = {"pan_speed_dps": 0.0, "tilt_speed_dps": 0.0}
                what = Send("gimbal_control", stop).describe()
                lines.append(_line(at, step.name, what, encode("gimbal_control", stop)))
                at += wait  # the rate and stop findings come within the time allowed
            else:
                data = encode(action.name, action.params)
                lines.append(_line(at, step.name, action.describe(), data))
                at += (wait if action.goals or action.check else 0.0) + action.pause
        attitude = plan.end
    for name, params in CENTRING:
        lines.append(_line(at, "(centre)", Send(name, params).describe(), encode(name, params)))
    return lines
