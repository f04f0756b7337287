"""The figures a comparison sets side by side, and how far apart each may be before it differs.

No band is made up here: each is the one the analysis (or the check) already judges by,
or the resolution the figure is measured with. A ratio or a rate differs when B's is
outside the band of A's that the analysis calls obeyed (75-133 %); a time read from the
feedback when the two are more than one feedback period apart (the feedback comes every
0.5 s, so a time measured from it is known to that); a lag by more than the lag the
analysis says (0.25 s); an angle by more than the tolerance; a zoom's scale by more than
the 10 % a zoom ratio is reached within; the feedback's period by more than the check's
25 %; a count (lost messages, CRC errors) when it is not the same. A figure only one
side measured is shown, not judged.
"""

from __future__ import annotations

from dataclasses import dataclass

from analyzer.analysis.camera.verdicts import TOLERANCE as SCALE_TOLERANCE
from analyzer.analysis.rates import LATE_S, RATE_OK
from analyzer.check.judge import Limits
from analyzer.feedback_track import FEEDBACK_PERIOD_S, FEEDBACK_TOLERANCE

SAME_COMMAND = 0.005  # the same command asks for the same (target, speed) to this


@dataclass(frozen=True)
class Rule:
    """How figure ``name`` is shown (``label``, ``form``, ``unit``) and compared: B within
    ``relative`` times A (low, high), or within ``absolute`` of A; ``band`` says why."""

    name: str
    label: str
    form: str
    unit: str = ""
    relative: tuple[float, float] | None = None
    absolute: float | None = None
    band: str = ""
    identity: bool = False  # what the command asked: apart, the two are not the same command

    def show(self, value: object) -> str:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return "-"
        return format(value, self.form)

    def apart(self, a: float, b: float) -> str:
        """Why ``a`` and ``b`` differ ('' when they do not)."""
        unit = f" {self.unit}" if self.unit else ""
        said = f"{self.label} {self.show(a)} | {self.show(b)}{unit}"
        if self.relative is not None:
            low, high = self.relative
            if a == 0:
                return "" if b == 0 else f"{said}: A is 0, B is not"
            share = b / a
            if low <= share <= high:
                return ""
            return f"{said}: B is {share * 100:.0f} % of A, outside {self.band}"
        gap = abs(b - a)
        if gap <= (self.absolute or 0.0) + 1e-9:
            return ""
        if self.identity:
            return f"{said}: not the same command"
        if not self.absolute:
            return f"{said}: {self.band}"
        return f"{said}: {format(gap, self.form)}{unit} apart, more than {self.band}"


def rules(tolerance_deg: float) -> tuple[Rule, ...]:
    """Every figure compared, in the order a pair shows them; angles within
    ``tolerance_deg`` (the analysis' --tolerance) are the same."""
    obeyed = _percent_band(*RATE_OK, "the band of an obeyed rate")
    speed = Limits().speed_tolerance
    period = f"one feedback period ({FEEDBACK_PERIOD_S:.2f} s, the resolution of a time read "
    period += "from the feedback)"
    angle = f"the tolerance ({tolerance_deg:g} deg)"
    return (
        Rule("target_deg", "target", "g", "deg", absolute=SAME_COMMAND, identity=True),
        Rule("asked_dps", "asked", ".1f", "deg/s", absolute=SAME_COMMAND, identity=True),
        Rule("pan_ratio", "pan ratio", ".2f", relative=RATE_OK, band=obeyed),
        Rule("tilt_ratio", "tilt ratio", ".2f", relative=RATE_OK, band=obeyed),
        Rule("lag_s", "lag", ".2f", "s", absolute=LATE_S, band=f"{LATE_S:g} s (a lag said)"),
        Rule("slew_dps", "slew", ".1f", "deg/s", relative=RATE_OK, band=obeyed),
        Rule(
            "rate_dps",
            "rate",
            ".1f",
            "deg/s",
            relative=(1 - speed, 1 + speed),
            band=_percent_band(1 - speed, 1 + speed, "the check's speed band"),
        ),
        Rule("response_s", "response", ".2f", "s", absolute=FEEDBACK_PERIOD_S, band=period),
        Rule("latency_s", "latency", ".2f", "s", absolute=FEEDBACK_PERIOD_S, band=period),
        Rule("settle_s", "settle", ".2f", "s", absolute=FEEDBACK_PERIOD_S, band=period),
        Rule("overshoot_deg", "overshoot", ".1f", "deg", absolute=tolerance_deg, band=angle),
        Rule("error_deg", "error", ".2f", "deg", absolute=tolerance_deg, band=angle),
        Rule("moved_deg", "moved", ".1f", "deg", absolute=tolerance_deg, band=angle),
        _within_share("scale", "scale", ".3g", "", SCALE_TOLERANCE, "a zoom ratio reached"),
        _within_share(
            "scale_back", "scale back", ".3g", "", SCALE_TOLERANCE, "a zoom ratio reached"
        ),
        _within_share(
            "period_s", "period", ".2f", "s", FEEDBACK_TOLERANCE, "the feedback's rhythm"
        ),
        Rule("lost", "lost", "g", band="not the same count"),
        Rule("crc_errors", "CRC errors", "g", band="not the same count"),
    )


def _within_share(name: str, label: str, form: str, unit: str, share: float, why: str) -> Rule:
    """A figure the same while B is within ``share`` of A either way (``why``: the rule
    of the analysis or the check that the share is)."""
    return Rule(
        name,
        label,
        form,
        unit,
        relative=(1 - share, 1 + share),
        band=f"{share * 100:.0f} % ({why})",
    )


def _percent_band(low: float, high: float, why: str) -> str:
    """A band of shares of A in words: "75-133 % (why)"."""
    return f"{low * 100:.0f}-{high * 100:.0f} % ({why})"
