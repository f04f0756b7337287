"""The response analyzer: decoded events in, /analysis/response findings out; no IO, no clock."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable
from typing import Any

from analyzer.analysis.findings import (
    CHECK_LIMIT,
    FEEDBACK_COMMAND,
    NOT_OBEYED,
    OBEYED,
    PARTIAL,
    UNKNOWN,
    ResponseFinding,
    cut_words,
)
from analyzer.analysis.health import FeedbackHealth
from analyzer.analysis.sample_window import SampleWindow
from analyzer.analysis.samples import MOTOR_YAW, PITCH, YAW, Sample, sample_from
from analyzer.analysis.settings import (
    DEFAULT_FLAG_ALLOWED_S,
    DEFAULT_TIME_ALLOWED_S,
    DEFAULT_TOLERANCE_DEG,
    FLAG_PERIODS,
    Settings,
)
from analyzer.analysis.stick_judge import LOOKBACK_S, StickJudge
from analyzer.analysis.streams import STREAM_GAP_S
from analyzer.analysis.target_check import TargetCheck, judge_target, target_check
from analyzer.analysis.tracking import (
    TrackingCheck,
    TrackingSession,
    judge_tracking,
    nothing_to_stop,
)
from analyzer.feedback_track import (
    GAP_THRESHOLD_S,
    damaged_feedback,
    feedback_stream,
)
from analyzer.protocol.event_columns import EventColumns
from analyzer.protocol.types import (
    CRC_MISMATCH,
    INCOMPLETE,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_ATTITUDE,
    Event,
)

# The topics whose events the analysis reads whole, those whose fields it reads (the
# commands); of every other event only the time counts.
EVENT_TOPICS = frozenset({TOPIC_GIMBAL_ATTITUDE, TOPIC_GIMBAL_RANGING, TOPIC_DIAGNOSTICS})
FIELD_TOPICS = frozenset({TOPIC_COMMAND})
# The fields read of a stick command (the most frequent; of others, all are made).
FIELDS_READ = {"gimbal_control": ("name", "component", "pan_speed_dps", "tilt_speed_dps")}

# A target re-sent within this of its last sending is still the same judgement; a judged
# one is held for its re-sends at most this long after its time allowed.
RESEND_GAP_S = STREAM_GAP_S
RESEND_HOLD_S = 30.0
FEEDBACK_WAIT_S = 2.0  # without feedback, a judgement waits this long past its deadline
# Times are compared with this much room, as t - a > b and t > a + b can round apart.
DUE_MARGIN_S = 1e-3
FC_ATTITUDE_FRESH_S = 3.0  # flight-controller attitude older than this counts as absent
DAMAGED_KINDS = frozenset({CRC_MISMATCH, INCOMPLETE})  # damaged feedback, in the health
# Commands that move the gimbal: each one ends what the previous motion command asked for.
MOTION = frozenset(
    {"gimbal_control", "specified_angle", "look_down", "forward", "tap_zoom", "tracking"}
)

BOTH = frozenset({PITCH, YAW})
# Which axes a motion command takes over (yaw stands for both yaw references).
AXES = {
    "gimbal_control": BOTH,
    "look_down": frozenset({PITCH}),
    "forward": BOTH,
    "tap_zoom": BOTH,
    "tracking": BOTH,
}


class ResponseAnalyzer:
    """``feed(event)`` and ``close()`` return /analysis/response events as they are decided."""

    def __init__(self, settings: Settings | None = None) -> None:
        self.settings = settings or Settings()
        self.health = FeedbackHealth()
        self.verdicts: Counter[str] = Counter()
        self.samples = SampleWindow()  # only those a pending judgement can still need
        self._targets: list[TargetCheck] = []
        self._tracking: list[TrackingCheck] = []
        self._sticks = StickJudge(self.samples, self.settings.tolerance_deg, FEEDBACK_WAIT_S)
        self._fc_attitude: float | None = None
        self._motion: tuple[str, float] | None = None
        self._at_limit: dict[str, float | None] = {PITCH: None, MOTOR_YAW: None}
        self._last_target: TargetCheck | None = None  # the last motion command's, if a target
        self._tracking_seen = False  # a feedback message has shown the tracking flag on
        self._session: TrackingSession | None = None  # tracking commands since the first
        # Before this time, time passing without feedback judges nothing (-inf: unknown).
        self._quiet_until = -math.inf

    # -- input ---------------------------------------------------------------------------

    def feed(self, event: Event) -> list[Event]:
        t, topic = event.time, event.topic
        out: list[ResponseFinding] = []
        if topic == TOPIC_GIMBAL_ATTITUDE:
            out += self.health.feedback(t, feedback_stream(event))
            sample = sample_from(t, event.fields, event.warnings)
            if sample is not None:
                self.samples.append(sample)
                self._tracking_seen = self._tracking_seen or sample.tracking
                self._follow_session(sample)
                out += self._limits(sample)
                out += self._settle(t, sample)
                self.samples.forget_before(min(self._needed(t), t - LOOKBACK_S))
        elif topic == TOPIC_GIMBAL_RANGING:
            out += self.health.feedback(t, feedback_stream(event))
            out += self._settle(t, None)
        elif topic == TOPIC_DIAGNOSTICS and event.fields.get("kind") in DAMAGED_KINDS:
            damaged = damaged_feedback(event)  # a bad CRC: it ends the silence before it
            out += self.health.error(t, feedback_stream(event), ends_silence=damaged)
            out += self._settle(t, None)
        else:  # the most frequent: time passes, perhaps a command (no list made for nothing)
            out = self._moment(t, topic, event.fields)
            return self._emit(out) if out else []
        self._quiet_until = -math.inf  # feedback or damage judged: when is the next one due?
        return self._emit(out) if out else []

    def _moment(self, t: float, topic: str, fields: dict[str, Any] | None) -> list[ResponseFinding]:
        """Any event but feedback and damage: its time passes; a command is judged."""
        out = self.health.tick(t)
        streams = self._sticks.streams
        if (t >= self._quiet_until or streams.reshaped) and (
            self._targets or self._tracking or self._sticks.active
        ):
            settled = self._settle(t, None)
            if settled:
                out += settled
            self._quiet_until = self._next_due() - DUE_MARGIN_S
            streams.reshaped = False
        if topic == TOPIC_UAV_ATTITUDE:
            self._fc_attitude = t
        elif topic == TOPIC_COMMAND and fields is not None:
            more = self._command(t, fields)
            if more:
                out += more
        return out

    def process(self, events: list[Event]) -> list[Event]:
        """As a pipeline stage (``analyzer.pipeline.Stage``): the findings of a batch.

        Findings already in the input (a recording made with this stage) are not judged
        again as input."""
        out: list[Event] = []
        feed = self.feed
        for event in events:
            if event.topic != TOPIC_ANALYSIS_RESPONSE:
                found = feed(event)
                if found:
                    out += found
        return out

    def process_segments(self, segments: Iterable[list[Event] | EventColumns]) -> list[Event]:
        """``process`` of a batch's events as the pipeline holds them (``Batch.segments``):
        of the events decoded in vectors, only those whose fields this reads are made
        into Events; the others are moments (their time and topic)."""
        out: list[Event] = []
        for segment in segments:
            if isinstance(segment, list):
                out += self.process(segment)
                continue
            for item in segment.moments(EVENT_TOPICS, FIELD_TOPICS, FIELDS_READ):
                if isinstance(item, tuple):
                    found = self._moment(*item)
                    if found:
                        out += self._emit(found)
                elif item.topic != TOPIC_ANALYSIS_RESPONSE:
                    out += self.feed(item)
        return out

    def close(self) -> list[Event]:
        """The end of the input: judge what is still open with what was seen."""
        out: list[ResponseFinding] = []
        last = self.samples.last
        end = last.time if last is not None else None
        for check in self._targets:
            if check.finding is None:
                self._judge_target(check, self._cut(check.time, check.deadline, ended=True), end)
            out.append(check.release())
        self._targets = []
        for tracking in self._tracking:
            why = self._cut(tracking.time, tracking.deadline, ended=True)
            out.append(self._judge_tracking(tracking, None, why))
        self._tracking = []
        out += self._sticks.close(self.health.last if self.health.last is not None else 0.0)
        out += self.health.close()
        return self._emit(out)

    def _emit(self, findings: list[ResponseFinding]) -> list[Event]:
        for finding in findings:
            self.verdicts[finding.verdict] += 1
        return [f.to_event() for f in findings]

    # -- commands -------------------------------------------------------------------------

    def _command(self, t: float, fields: dict[str, Any]) -> list[ResponseFinding]:
        name = str(fields.get("name", ""))
        out: list[ResponseFinding] = []
        if name == "gimbal_control":
            return self._gimbal_control(t, fields)
        if name not in MOTION and name != "tracking_stop":
            return out
        self._quiet_until = -math.inf
        session = self._session
        if name == "tracking" and session is not None:
            session.update(t)  # the box moved: the same session
            # the gimbal turns to the box: the tracker takes over from what came before
            return self._interrupt(t, name, AXES[name])
        allowed = self.settings.time_allowed_s
        fresh = self._fc_attitude is not None and t - self._fc_attitude <= FC_ATTITUDE_FRESH_S
        check = target_check(name, t, fields, t + allowed, fresh)
        if check is not None:
            tolerance = self.settings.tolerance_deg
            pending = next((c for c in self._targets if c.repeated_by(check, tolerance)), None)
            if pending is not None:  # the same target re-sent: part of its judgement
                pending.resent(t)
                return out
        if name in MOTION:
            axes = AXES.get(name) or frozenset({PITCH if fields.get("axis") == "pitch" else YAW})
            if name == "specified_angle" and fields.get("axis") not in ("pitch", "yaw"):
                axes = frozenset()  # zoom
            out += self._interrupt(t, name, axes)
            self._motion = (name, t)
            self._last_target = check
        if check is not None:
            self._targets.append(check)
        if name in ("tracking", "tracking_stop"):
            for old in self._tracking:
                why = f"{name} came {t - old.time:.1f} s later" if t < old.deadline else ""
                out.append(self._judge_tracking(old, None, why))
            self._tracking = []
            before = self._before(t)
            if name == "tracking":
                session = self._session = TrackingSession(t)
            else:
                self._session = None
            if name == "tracking_stop" and not (before is not None and before.tracking):
                found = nothing_to_stop(t, before, seen_on=self._tracking_seen, session=session)
                out.append(found)
            else:
                flag_allowed = self.settings.flag_allowed_s
                want = name == "tracking"
                self._tracking.append(TrackingCheck(name, t, want, t + flag_allowed, session))
        return out

    def _follow_session(self, sample: Sample) -> None:
        """The flag seen on starts counting; seen off after that, the session is over."""
        session = self._session
        if session is None:
            return
        if sample.tracking:
            session.seen_on = True
        elif session.seen_on and sample.time > session.last:
            self._session = None  # the gimbal let go of its target

    def _gimbal_control(self, t: float, fields: dict[str, Any]) -> list[ResponseFinding]:
        """One command of a stick stream: targets end at a speed, movements open and close."""
        pan, tilt = fields.get("pan_speed_dps", 0.0), fields.get("tilt_speed_dps", 0.0)
        if pan.__class__ is not float or tilt.__class__ is not float:
            pan, tilt = _speed(pan), _speed(tilt)
        out: list[ResponseFinding] = []
        if (pan != 0 or tilt != 0) and self._targets:
            # A speed takes over both axes; zeros (a centred stick) leave targets alone.
            out += self._end_targets(t, "gimbal_control", BOTH)
        component = fields.get("component")
        if component.__class__ is not str or not component:
            component = str(component or "gimbal")
        start = self._sticks.command(t, component, pan, tilt, self._target_met)
        if start is not None:
            motion = self._motion
            if motion is None or motion[1] != start or motion[0] != "gimbal_control":
                self._motion = ("gimbal_control", start)
        return out

    def _target_met(self) -> bool:
        """The last motion command was a target the latest feedback shows the gimbal at
        (so it had nothing more to do for it)."""
        check, last = self._last_target, self.samples.last
        return check is not None and last is not None and check.met(last, self.settings)

    def _end_targets(self, t: float, name: str, axes: frozenset[str]) -> list[ResponseFinding]:
        """A new motion command: earlier targets on its axes are judged as they stand."""
        out: list[ResponseFinding] = []
        keep: list[TargetCheck] = []
        for check in self._targets:
            if check.axes() & axes:
                if check.finding is None:
                    why = f"{name} came {t - check.time:.1f} s later" if t < check.deadline else ""
                    self._judge_target(check, why, t)
                out.append(check.release())
            else:
                keep.append(check)
        self._targets = keep
        return out

    def _interrupt(self, t: float, name: str, axes: frozenset[str]) -> list[ResponseFinding]:
        """A motion command other than gimbal_control: earlier targets on its axes, and
        the stick streams, end here; what waits for feedback is judged on what came."""
        return self._end_targets(t, name, axes) + self._sticks.interrupt(t, name)

    # -- time passing ---------------------------------------------------------------------

    def _settle(self, t: float, sample: Sample | None) -> list[ResponseFinding]:
        """Judge what has had its time; ``sample`` is a new attitude sample at ``t``."""
        out: list[ResponseFinding] = []
        late = FEEDBACK_WAIT_S
        if self._targets:
            keep: list[TargetCheck] = []
            for check in self._targets:
                if check.finding is None and t > check.deadline + (
                    0.0 if sample is not None else late
                ):
                    cut = "" if sample is not None else self._cut(check.time, check.deadline)
                    self._judge_target(check, cut, check.deadline)
                if check.finding is not None and (
                    t - check.last_sent > RESEND_GAP_S or t - check.deadline > RESEND_HOLD_S
                ):
                    out.append(check.release())
                else:
                    keep.append(check)
            self._targets = keep
        if self._tracking:
            still: list[TrackingCheck] = []
            for tracking in self._tracking:
                if sample is not None and sample.tracking == tracking.want and t > tracking.time:
                    out.append(self._judge_tracking(tracking, sample, ""))
                elif t > tracking.deadline + (0.0 if sample is not None else late):
                    cut = "" if sample is not None else self._cut(tracking.time, tracking.deadline)
                    out.append(self._judge_tracking(tracking, None, cut))
                else:
                    still.append(tracking)
            self._tracking = still
        if self._sticks.active:
            out += self._sticks.settle(t, sample)
        return out

    def _next_due(self) -> float:
        """The earliest time at which time passing without feedback judges something."""
        late = FEEDBACK_WAIT_S
        due = self._sticks.due()
        for check in self._targets:
            if check.finding is None:
                due = min(due, check.deadline + late)
            else:
                due = min(due, check.last_sent + RESEND_GAP_S, check.deadline + RESEND_HOLD_S)
        for tracking in self._tracking:
            due = min(due, tracking.deadline + late)
        return due

    def _cut(self, since: float, until: float, *, ended: bool = False) -> str:
        """What ended the feedback before ``until`` (for a command at ``since``), in words;
        '' when the feedback reached ``until`` (``analyzer.analysis.findings.cut_words``)."""
        last = self.samples.last
        seen = last.time if last is not None else None
        end = self.health.last if ended else None
        return cut_words(since, until, seen, end, FEEDBACK_WAIT_S)

    def _between(self, start: float, end: float) -> list[Sample]:
        return self.samples.between(start, end)

    def _before(self, t: float) -> Sample | None:
        return self.samples.before(t)

    def _needed(self, now: float) -> float:
        """The earliest time whose samples a judgement still to be made can look at: a
        pending check's command, a stick movement's first command, the end of one whose
        stop is watched, or (for commands to come) now."""
        times = [now]
        times += [check.time for check in self._targets if check.finding is None]
        times += [tracking.time for tracking in self._tracking]
        times += self._sticks.pending()
        return min(times)

    def earliest_pending(self) -> float | None:
        """No finding still to come carries an earlier time than this (for input in time
        order): a pending check's command, a stick movement, the motion command a limit
        finding would name, the feedback window or silence still open. None before any
        input."""
        now = self.health.last
        if now is None:
            return None
        times = [self._needed(now), *self.health.open_since()]
        times += [check.time for check in self._targets if check.finding is not None]
        if self._motion is not None:
            times.append(self._motion[1])
        return min(times)

    # -- judgements -----------------------------------------------------------------------

    def _judge_target(self, check: TargetCheck, cut_short: str, end: float | None) -> None:
        """Judge ``check`` on the feedback up to ``end`` (its deadline at most); a silence
        that lost messages up to there cut it short as the end of the feedback would."""
        stop = check.deadline if end is None else min(end, check.deadline)
        settings = self.settings
        seen = self._between(check.time, stop)
        last = seen[-1].time if seen else check.time
        if not cut_short and stop - last >= GAP_THRESHOLD_S:
            cut_short = f"the feedback stopped {last - check.time:.1f} s after it"
            if not seen:
                cut_short = "the feedback stopped before it"
        check.finding = judge_target(
            check,
            self._before(check.time),
            seen,
            settings.tolerance_deg,
            settings.time_allowed_s,
            cut_short,
        )

    def _judge_tracking(
        self, check: TrackingCheck, sample: Sample | None, cut_short: str
    ) -> ResponseFinding:
        seen = [] if sample is not None else self._between(check.time, check.deadline)
        return judge_tracking(check, sample, seen, cut_short, self.settings.flag_allowed_s)

    def _limits(self, sample: Sample) -> list[ResponseFinding]:
        out: list[ResponseFinding] = []
        for axis in (PITCH, MOTOR_YAW):
            limit = sample.at_limit(axis)
            if limit is not None and self._at_limit[axis] is None:
                name, t = self._motion if self._motion else (FEEDBACK_COMMAND, sample.time)
                verdict = PARTIAL if self._motion else UNKNOWN
                word = "pitch" if axis == PITCH else "yaw motor"
                text = (
                    f"the gimbal is at its {word} limit {limit:.1f} deg "
                    f"{sample.time - t:.1f} s after {name}: it cannot turn further that way"
                )
                extra = {"axis": axis, "limit_deg": limit, "observed_at": sample.time}
                out.append(ResponseFinding(name, t, CHECK_LIMIT, verdict, text, extra))
            self._at_limit[axis] = limit
        return out


def _speed(value: Any) -> float:
    """A gimbal_control's speed as a float (0 for a value that is no number)."""
    return float(value) if isinstance(value, (int, float)) else 0.0


__all__ = [
    "DEFAULT_FLAG_ALLOWED_S",
    "DEFAULT_TIME_ALLOWED_S",
    "DEFAULT_TOLERANCE_DEG",
    "FLAG_PERIODS",
    "NOT_OBEYED",
    "OBEYED",
    "PARTIAL",
    "UNKNOWN",
    "ResponseAnalyzer",
    "Settings",
]
