"""The camera judgement as a pipeline stage: camera commands in, /analysis/response findings out.

Each camera command opens a window: a continuous zoom until its stop (and the moment the
lens takes to stop), a zoom to a ratio or by a factor for the time allowed, a palette or a
PiP change for a second; the next command of the same kind ends it sooner. Once the input
has passed the window's end (and the video reaches it), the frames from just before the
command to the window's end are decoded (from the keyframe before) and judged; nothing
else of the video is decoded.
"""

from __future__ import annotations

import itertools
import math
from collections import Counter
from dataclasses import dataclass

import cv2
import numpy as np

from analyzer.analysis.camera.commands import (
    COLOURS,
    DIGITAL,
    DIRECTION,
    LAYOUT,
    OPTICAL,
    PALETTE,
    STOP,
    Asked,
    asked,
)
from analyzer.analysis.camera.follow import (
    LOST,
    TOO_LITTLE_TEXTURE,
    FeatureCache,
    follow,
)
from analyzer.analysis.camera.layout import layout_change
from analyzer.analysis.camera.motion import features, motion, where
from analyzer.analysis.camera.palette import palette_change
from analyzer.analysis.camera.source import VideoSource
from analyzer.analysis.camera.telemetry import Telemetry
from analyzer.analysis.camera.verdicts import Seen, ZoomRange, judge
from analyzer.analysis.camera.weak_links import doubt_words
from analyzer.analysis.findings import ResponseFinding
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, TOPIC_COMMAND, Event
from analyzer.video.decode import Picture

SETTLE_S = 0.4  # a lens told to stop has stopped this long after
CHANGE_S = 1.0  # a palette or a PiP layout shows within this
BEFORE_S = 1.0  # pictures from this long before the command are decoded
MAX_FRAME_AGE_S = 0.5  # a frame further than this from the moment it stands for: a gap
GAP_S = 1.0  # frames further apart than this inside a window: a gap in the video
WAIT_S = 0.5  # the telemetry after a window's end that is waited for before judging
# A zoom whose video ends before its window did is judged if the picture kept its scale
# (within 3 %) over its last second.
SETTLED_S, SETTLED_WITHIN = 1.0, 0.03
THERMAL_NAMES = ("thermal", "sub2")  # the document's thermal stream (subtype 2)
TAP_TURN_S = 1.0  # tap_zoom: the gimbal has turned to the tapped point by then
DRIFT_S = 0.3  # the view's drift before a tap_zoom is measured over this
PICTURE_WIDTH = 240  # the JPEGs kept for the report
MAX_PICTURES = 200


@dataclass
class _Pending:
    """A camera command waiting for its window to end."""

    command: str
    time: float
    asked: Asked
    end: float
    open: bool = False  # a continuous zoom that no stop has ended yet


class CameraJudge:
    """Judges camera commands from ``video`` (a ``VideoSource``); a pipeline Stage.

    ``time_allowed_s`` is the time a zoom to a ratio or by a factor has to settle (the
    analysis' time allowed). With ``keep_pictures`` the two frames of each finding are
    kept as small JPEGs in ``pictures`` ({(stream, time): jpeg}) for the report, and the
    findings (as dicts) in ``judged``."""

    def __init__(
        self, video: VideoSource, time_allowed_s: float = 5.0, *, keep_pictures: bool = False
    ) -> None:
        self.video = video
        self.time_allowed_s = time_allowed_s
        self.keep_pictures = keep_pictures
        self.pictures: dict[tuple[str, float], bytes] = {}
        self.judged: list[dict[str, object]] = []  # with ``keep_pictures``: the findings
        self.telemetry = Telemetry()
        self.verdicts: Counter[str] = Counter()
        self.streams = video.streams()
        self._pending: list[_Pending] = []
        self._zoom: ZoomRange | None = None
        self._palette = ""  # the palette the camera was last seen to take
        self._now = -math.inf
        self._settled = False  # the last zoom followed kept its scale over its last second

    # -- the stage -----------------------------------------------------------------------

    def process(self, events: list[Event]) -> list[Event]:
        for event in events:
            if event.topic == TOPIC_ANALYSIS_RESPONSE:
                continue
            self._now = max(self._now, event.time)
            if event.topic == TOPIC_COMMAND:
                self._command(event.time, event.fields)
            else:
                self.telemetry.add(event)
        return self._emit(self._judge_due(final=False))

    def close(self) -> list[Event]:
        return self._emit(self._judge_due(final=True))

    def earliest_pending(self) -> float | None:
        """No finding still to come has an earlier time (None: none is pending)."""
        return min((p.time for p in self._pending), default=None)

    def _emit(self, findings: list[ResponseFinding]) -> list[Event]:
        for finding in findings:
            self.verdicts[finding.verdict] += 1
        return [f.to_event() for f in findings]

    # -- commands ------------------------------------------------------------------------

    def _command(self, t: float, fields: dict[str, object]) -> None:
        wanted = asked(dict(fields))
        if wanted is None:
            return
        same = [p for p in self._pending if p.asked.group == wanted.group and p.end > t]
        if wanted.kind == STOP:
            for pending in same:
                if pending.open:
                    pending.end, pending.open = t + SETTLE_S, False
            return
        for pending in same:
            if pending.open and wanted.kind == DIRECTION and wanted.value == pending.asked.value:
                return  # the same zoom sent again while it goes on (a button held)
        for pending in same:
            pending.end, pending.open = max(pending.time, t - 0.05), False
        if wanted.kind in (PALETTE, LAYOUT):
            end = t + min(CHANGE_S, self.time_allowed_s)
        else:
            end = t + self.time_allowed_s
        name = str(fields.get("name", ""))
        self._pending.append(_Pending(name, t, wanted, end, wanted.kind == DIRECTION))

    # -- judging -------------------------------------------------------------------------

    def _judge_due(self, *, final: bool) -> list[ResponseFinding]:
        reach = self.video.until()
        out: list[ResponseFinding] = []
        keep: list[_Pending] = []
        for pending in sorted(self._pending, key=lambda p: p.time):
            ready = self._now >= pending.end + WAIT_S and reach >= pending.end
            if final or ready:
                out.append(self._judge(pending))
            else:
                keep.append(pending)
        self._pending = keep
        oldest = min([p.time for p in keep] + [self._now])
        self.telemetry.forget_before(oldest - BEFORE_S)
        return out

    def _judge(self, pending: _Pending) -> ResponseFinding:
        wanted = pending.asked
        if wanted.group in (OPTICAL, DIGITAL) and self._zoom is None:
            self._zoom = ZoomRange(self.telemetry.max_zoom)
        zoom = self._zoom if wanted.group == OPTICAL else None
        stream = self._stream(wanted.group)
        shown: dict[float, Picture] = {}
        if stream is None:
            seen = Seen("", problem="no thermal stream was recorded (--video thermal)")
        else:
            seen = self._look(pending, stream, shown)
        already = wanted.kind == PALETTE and wanted.palette == self._palette
        verdict = judge(pending.command, pending.time, wanted, seen, zoom, already)
        finding = verdict.finding
        if zoom is not None:
            self._zoom = verdict.zoom  # what this command taught of the optical zoom
        if wanted.kind == PALETTE and finding.verdict == "obeyed":
            self._palette = wanted.palette
        if self.keep_pictures and len(self.judged) < MAX_PICTURES // 2:
            self._keep(seen, shown)
            self.judged.append(finding.to_event().to_dict())
        return finding

    def _stream(self, group: str) -> str | None:
        names = self.streams
        if group == COLOURS:
            return next((n for n in THERMAL_NAMES if n in names), None)
        for name in ("main", "sub1"):
            if name in names:
                return name
        others = [n for n in names if n not in THERMAL_NAMES] or names
        return others[0] if others else None

    def _look(self, pending: _Pending, stream: str, shown: dict[float, Picture]) -> Seen:
        """What the video shows for a command (``shown`` gets its pictures, by time)."""
        t, end = pending.time, pending.end
        pictures = self.video.pictures(stream, t - BEFORE_S, end)
        shown.update((p.time, p) for p in pictures)
        before = [p for p in pictures if p.time < t]
        topic = f"/camera/{stream}"
        if not before or t - before[-1].time > MAX_FRAME_AGE_S:
            why = (
                f"{t - before[-1].time:.1f} s older" if before else "not in the recording before it"
            )
            return Seen(
                stream, problem=f"no video at that moment: the last frame of {topic} is {why}"
            )
        first = before[-1]
        run = [first] + [p for p in pictures if first.time < p.time <= end]
        after = run[-1]
        cut = after is first or end - after.time > MAX_FRAME_AGE_S
        if cut and not (pending.asked.zoom and after.time - t >= SETTLED_S + 0.5):
            seen = f"{after.time - t:.1f} s" if after is not first else "no time"
            return Seen(
                stream,
                first.time,
                problem=f"the video of {topic} stops {seen} after the command, before the "
                f"{'zoom' if pending.asked.zoom else 'change'} could be seen through",
            )
        seen_now = Seen(stream, first.time, after.time)
        images = [p.rgb for p in run]
        if pending.asked.kind == PALETTE:
            seen_now.changed = palette_change(images) is not None
            return seen_now
        if pending.asked.kind == LAYOUT:
            seen_now.changed = layout_change(images) is not None
            return seen_now
        found = self._scale(pending, run, seen_now, topic, before[:-1])
        if cut and not found.problem and not self._settled:
            found.problem = (
                f"the video of {topic} stops {after.time - t:.1f} s after the command, while "
                "the picture still zoomed"
            )
        return found

    def _scale(
        self,
        pending: _Pending,
        run: list[Picture],
        seen: Seen,
        topic: str,
        shown_before: list[Picture],
    ) -> Seen:
        times = [p.time for p in run]
        telemetry = self.telemetry
        followed = follow(
            [p.rgb for p in run],
            FeatureCache([p.rgb for p in run]),
            lambda a, b: telemetry.explained_and_doubt(times[a], times[b]),
            times,
        )
        settled_early = (
            not followed.complete
            and pending.asked.kind != DIRECTION
            and times[followed.reached] - pending.time >= SETTLED_S + 0.5
            and followed.settled(times, SETTLED_S, SETTLED_WITHIN)
        )
        if settled_early:  # lost after the zoom had settled (the gimbal turned away): judged
            seen.after = times[followed.reached]
        elif not followed.complete:
            gap = max((b - a for a, b in itertools.pairwise(times)), default=0.0)
            if followed.problem == TOO_LITTLE_TEXTURE:
                seen.problem = "too little texture in the picture to measure its scale"
            elif followed.problem == LOST:
                seen.problem = "the picture could not be followed from one frame to the next"
            elif followed.doubted is not None:
                seen.problem = f"cannot tell: {doubt_words(*followed.doubted, pending.time)}"
            if gap > GAP_S:
                seen.problem += f" across a {gap:.1f} s gap in the video of {topic}"
            return seen
        seen.scale, seen.raw_scale = followed.scale, followed.raw_scale
        seen.uncertainty = followed.uncertainty
        self._settled = followed.settled(times, SETTLED_S, SETTLED_WITHIN)
        tap = pending.asked.tap
        if tap is not None:
            earlier = [p for p in shown_before if run[0].time - p.time >= DRIFT_S]
            drift = _drift(earlier[-1] if earlier else None, run[0])
            seen.tap_offset = _nearest(followed.path[1:], times, run[0].rgb.shape, tap, drift)
        return seen

    def _keep(self, seen: Seen, shown: dict[float, Picture]) -> None:
        for moment in (seen.before, seen.after):
            picture = shown.get(moment) if moment is not None else None
            if picture is None or moment is None:
                continue
            rgb = picture.rgb
            height = max(2, round(rgb.shape[0] * PICTURE_WIDTH / rgb.shape[1]))
            small = cv2.resize(rgb, (PICTURE_WIDTH, height), interpolation=cv2.INTER_AREA)
            ok, jpeg = cv2.imencode(".jpg", np.ascontiguousarray(small[:, :, ::-1]))
            if ok:  # by the time as the finding carries it (to the millisecond)
                self.pictures[(seen.stream, round(moment, 3))] = jpeg.tobytes()


def _nearest(
    path: tuple[tuple[int, np.ndarray], ...],
    times: list[float],
    shape: tuple[int, ...],
    tap: tuple[float, float],
    drift: tuple[float, float],
) -> float | None:
    """How near the tapped point the lens came to point, in the picture before the
    command (fractions of its half width / height): each frame's centre is mapped back
    into that picture over the first TAP_TURN_S, less the drift the view had before the
    command (the aircraft flying on carries the view along: pixels per second)."""
    h, w = shape[:2]
    cx, cy = (w - 1) / 2, (h - 1) / 2
    tapped = (cx + tap[0] * w / 2, cy + tap[1] * h / 2)
    offsets = []
    for index, homography in path:
        elapsed = times[index] - times[0]
        if elapsed > TAP_TURN_S:
            break
        try:
            back = np.linalg.solve(homography, np.array([cx, cy, 1.0]))
        except np.linalg.LinAlgError:
            continue
        if back[2] <= 0:
            continue
        x = back[0] / back[2] - drift[0] * elapsed
        y = back[1] / back[2] - drift[1] * elapsed
        offsets.append(math.hypot((x - tapped[0]) / (w / 2), (y - tapped[1]) / (h / 2)))
    return min(offsets) if offsets else None


def _drift(earlier: Picture | None, first: Picture) -> tuple[float, float]:
    """How fast the view moved over the scene before the command, in pixels of ``first``
    per second (the centre's scene point, from ``earlier`` to ``first``)."""
    if earlier is None or first.time <= earlier.time:
        return 0.0, 0.0
    found = motion(features(earlier.rgb), features(first.rgb))
    if found is None:
        return 0.0, 0.0
    h, w = first.rgb.shape[:2]
    cx, cy = (w - 1) / 2, (h - 1) / 2
    landed = where(found.homography, cx, cy)
    if landed is None:
        return 0.0, 0.0
    span = first.time - earlier.time
    return (cx - landed[0]) / span, (cy - landed[1]) / span
