"""Which yaw a specified_angle yaw target is judged on (psi from north, or the motor), and why.

The document (0x08): DATA4 = 1 names the airframe frame, anything else the geodetic
one; a directional angle is from north "when the flight control attitude is accessed",
else from the UAV's nose. A capture does not always show whether the gimbal has that
attitude (0x0000FF13 travels on the CAN bus, never on the IDU's TCP port), but the
feedback does: a gimbal that knows its heading reports ``psi`` offset from ``Motor_psi``.
"""

from __future__ import annotations

from dataclasses import dataclass
from statistics import median

from analyzer.analysis.findings import NOT_OBEYED, OBEYED, UNKNOWN
from analyzer.analysis.samples import MOTOR_YAW, YAW, Sample
from analyzer.analysis.targets import AxisGoal, AxisResult
from analyzer.analysis.yaw_geometry import angle_error, psi_offset
from analyzer.protocol.response_fields import REFERENCE_AIRFRAME, REFERENCE_NORTH

NO_OFFSET_DEG = 0.5  # psi this close to Motor_psi: the gimbal reports no heading of its own
STEADY_DEG = 2.0  # offsets spread less than this are reported as one number

REASON_COMMAND = "command DATA4 = 1"
REASON_FF13 = "FF13 present"
REASON_NO_SOURCE = "capture shows no heading source; psi used"
REASON_NO_HEADING = "no FF13 on the bus; psi follows motor yaw"
REASON_NO_FEEDBACK = "no FF13 on the bus; no feedback to compare psi with motor yaw"


@dataclass(frozen=True)
class YawCommand:
    """A specified_angle yaw target and what was known when it was sent."""

    target: float  # as the command gave it (0..360)
    airframe: bool  # DATA4 = 1
    fc_attitude: bool  # the flight controller's attitude (FF13) was seen shortly before
    stream: bool  # the command came over TCP / UART, where FF13 is never seen


@dataclass(frozen=True)
class YawReference:
    """The reference a yaw target is judged in, and the evidence for it."""

    name: str  # REFERENCE_NORTH or REFERENCE_AIRFRAME
    reason: str

    @property
    def axis(self) -> str:
        return YAW if self.name == REFERENCE_NORTH else MOTOR_YAW

    def note(self) -> str:
        where = "north" if self.name == REFERENCE_NORTH else "the airframe's nose"
        return f"yaw measured from {where} ({self.reason})"

    def goal(self, command: YawCommand) -> AxisGoal:
        return AxisGoal(self.axis, command.target, "yaw")


def _offset_text(offsets: list[float]) -> str:
    low, high = min(offsets), max(offsets)
    if high - low < STEADY_DEG:
        return f"{median(offsets):.1f} deg"
    return f"{low:.1f} to {high:.1f} deg"


def choose_reference(command: YawCommand, samples: list[Sample]) -> YawReference:
    """The reference of ``command``, judged with the feedback around it (``samples``)."""
    if command.airframe:
        return YawReference(REFERENCE_AIRFRAME, REASON_COMMAND)
    if command.fc_attitude:
        return YawReference(REFERENCE_NORTH, REASON_FF13)
    offsets = [psi_offset(s) for s in samples]
    heading = [o for o in offsets if abs(o) > NO_OFFSET_DEG]
    if heading:
        return YawReference(REFERENCE_NORTH, f"psi offset from motor yaw: {_offset_text(heading)}")
    if command.stream:
        return YawReference(REFERENCE_NORTH, REASON_NO_SOURCE)
    reason = REASON_NO_HEADING if samples else REASON_NO_FEEDBACK
    return YawReference(REFERENCE_AIRFRAME, reason)


def wrong_frame(
    reference: YawReference, result: AxisResult, last: Sample | None, tolerance: float
) -> AxisResult:
    """A result that missed its target but hit it in the other frame says so (not obeyed).

    A gimbal that takes a geodetic target from the nose (or an airframe one from north)
    ends where the other reference reaches the target; the frames only differ when psi
    is offset from the motor yaw.
    """
    if result.verdict in (OBEYED, UNKNOWN) or last is None:
        return result
    if abs(psi_offset(last)) <= tolerance:
        return result
    goal = result.goal
    other = MOTOR_YAW if goal.axis == YAW else YAW
    if abs(angle_error(other, goal.target, last)) > tolerance:
        return result
    target = f"{goal.target:.1f}"
    off = f"{abs(result.error_deg or 0.0):.1f} deg off"
    if goal.axis == YAW:
        text = (
            f"yaw {target} from north not reached: the gimbal turned to {target} from the "
            f"airframe's nose instead (psi {last.yaw:.1f}, {off}), as if DATA4 were 1"
        )
    else:
        text = (
            f"yaw {target} from the airframe's nose not reached: the gimbal turned to "
            f"{target} from north instead (motor yaw {last.motor_yaw:.1f}, {off}), "
            "as if DATA4 were not 1"
        )
    return AxisResult(
        goal,
        NOT_OBEYED,
        text,
        error_deg=result.error_deg,
        start_deg=result.start_deg,
        final_deg=result.final_deg,
    )
