"""The report's camera section: a strip along the flight and a before / after pair of
pictures for the worst commands (the command's moment, then the verdict's)."""

from __future__ import annotations

import base64
import html
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from analyzer.report.decimate import Decimator
from analyzer.report.finding_groups import whole_run
from analyzer.report.tables import clock
from analyzer.scene.timeline import TimedPicture  # a camera picture: stream, time, jpeg
from analyzer.timefmt import UTC, TimeZone

STRIP_SIZE = 8  # pictures in the strip along the flight
MAX_FINDING_PICTURES = 40  # findings shown with their pictures
SHOWN_VERDICTS = ("not_obeyed", "partial")
MAX_TICKS = 2000  # picture ticks on the timeline

CSS = """
.strip { display: flex; gap: 4px; margin: 6px 0 2px; }
.strip figure, .seen figure { margin: 0; flex: 1 1 0; min-width: 0; }
.strip img { width: 100%; display: block; border-radius: 2px; }
figcaption { font-size: 11px; color: #555; }
.timeline { position: relative; height: 14px; background: #f0f0f0; margin: 2px 0 16px; }
.timeline span { position: absolute; top: 0; width: 2px; height: 14px; }
.tick-picture { background: #4e98e2; } .tick-not_obeyed { background: #d62728; }
.tick-partial { background: #ff9800; }
.seen { display: grid; grid-template-columns: 200px 200px 1fr; gap: 6px 14px;
        align-items: start; }
.seen img { width: 200px; display: block; border-radius: 2px; }
"""


def picture_jpeg(picture: TimedPicture) -> bytes:
    """The JPEG shown for ``picture``: the one place where a picture's image is asked for
    (a picture of ``analyzer.scene.timeline`` draws its overlay in then, and only then)."""
    return picture.jpeg


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _img(picture: TimedPicture, alt: str) -> str:
    data = base64.b64encode(picture_jpeg(picture)).decode("ascii")
    return f'<img src="data:image/jpeg;base64,{data}" alt="{_e(alt)}">'


def verdict_moment(finding: dict[str, Any]) -> float | None:
    """When the verdict was decided: the feedback that decided it, else the command's time
    plus its response or duration; None for a finding with no such moment."""
    observed = finding.get("observed_at")
    if isinstance(observed, (int, float)) and not isinstance(observed, bool):
        return float(observed)
    for name in ("response_s", "duration_s"):
        value = finding.get(name)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(finding["time"]) + float(value)
    return None


@dataclass(frozen=True)
class Wanted:
    """A moment a picture is wanted for: the last picture at or before it (``before``), or
    the one nearest to it taken after ``later_than``."""

    time: float
    before: bool = False
    later_than: float | None = None

    def better(self, t: float, best: float | None) -> bool:
        """Whether a picture taken at ``t`` fits better than the best one so far."""
        if self.before:
            return t <= self.time and (best is None or t > best)
        if self.later_than is not None and t <= self.later_than:
            return False
        return best is None or abs(t - self.time) < abs(best - self.time)


class PictureChoice:
    """Keeps, out of a stream of pictures, only the one that fits each wanted moment best."""

    def __init__(self, wanted: Iterable[Wanted], strip: Sequence[Wanted] = ()) -> None:
        self.strip = list(strip)  # the moments of the strip along the flight
        self.best: dict[Wanted, TimedPicture] = {w: _NONE for w in wanted}
        self.count = 0
        self.streams: set[str] = set()
        self.first: float | None = None
        self.last: float | None = None
        self.times = Decimator((), MAX_TICKS)  # (time,) for the timeline's ticks

    def offer(self, picture: TimedPicture) -> None:
        t = picture.time
        self.count += 1
        self.streams.add(picture.stream)
        self.first = t if self.first is None else min(self.first, t)
        self.last = t if self.last is None else max(self.last, t)
        self.times.add((t,))
        for want, best in self.best.items():
            if want.better(t, None if best is _NONE else best.time):
                self.best[want] = picture

    def get(self, want: Wanted) -> TimedPicture | None:
        found = self.best.get(want, _NONE)
        return None if found is _NONE else found


@dataclass(frozen=True)
class _NoPicture:
    stream: str = ""
    time: float = 0.0
    jpeg: bytes = b""


_NONE: TimedPicture = _NoPicture()


def shown_findings(examples: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """The findings that get their pictures: commands not (fully) obeyed, worst first."""
    failed = [f for f in examples if str(f.get("verdict")) in SHOWN_VERDICTS]
    return [f for f in failed if not whole_run(f)][:MAX_FINDING_PICTURES]


def strip_moments(first: float, last: float) -> list[Wanted]:
    span = last - first
    if span <= 0:
        return [Wanted(first)]
    return [Wanted(first + span * i / (STRIP_SIZE - 1)) for i in range(STRIP_SIZE)]


def wanted_moments(findings: Sequence[dict[str, Any]]) -> list[Wanted]:
    """Every moment a picture is wanted for: each finding's pair."""
    wanted = []
    for finding in findings:
        wanted.append(before_command(finding))
        after = at_verdict(finding)
        if after is not None:
            wanted.append(after)
    return wanted


def before_command(finding: dict[str, Any]) -> Wanted:
    """The last picture taken at or before the command."""
    return Wanted(float(finding["time"]), before=True)


def at_verdict(finding: dict[str, Any]) -> Wanted | None:
    """The picture nearest to the moment the verdict was decided, taken after the command."""
    moment = verdict_moment(finding)
    if moment is None:
        return None
    return Wanted(moment, later_than=float(finding["time"]))


def choose(
    pictures: Iterable[TimedPicture], first: float, last: float, findings: Sequence[dict[str, Any]]
) -> PictureChoice:
    """Reads the pictures once, keeping only those the section shows (the strip spans the
    flight, ``first`` to ``last``)."""
    strip = strip_moments(first, last)
    choice = PictureChoice([*strip, *wanted_moments(findings)], strip)
    for picture in pictures:
        choice.offer(picture)
    return choice


def _figure(picture: TimedPicture | None, what: str, t: float, zone: TimeZone) -> str:
    if picture is None:
        return f'<figure><p class="empty">no picture {_e(what)}</p></figure>'
    offset = picture.time - t
    return (
        f"<figure>{_img(picture, f'camera {what}')}<figcaption>{_e(what)}: "
        f"{_e(clock(picture.time, zone))} ({offset:+.1f} s)</figcaption></figure>"
    )


def camera_section(
    choice: PictureChoice, findings: Sequence[dict[str, Any]], zone: TimeZone = UTC
) -> str:
    """The HTML of "What the camera saw" (empty when the input has no camera pictures),
    its times in ``zone``."""
    if not choice.count or choice.first is None or choice.last is None:
        return ""
    first, last = choice.first, choice.last
    span = last - first
    strip: list[TimedPicture] = []
    for want in choice.strip:
        picture = choice.get(want)
        if picture is not None and picture not in strip:
            strip.append(picture)
    out = [
        "<h2>What the camera saw</h2>",
        f'<p class="small">{choice.count:,} pictures of {_e(", ".join(sorted(choice.streams)))}'
        f" from {_e(clock(first, zone))} to {_e(clock(last, zone))}. Blue ticks: pictures; red and "
        "orange: the commands shown below, not obeyed / partly obeyed.</p>",
        '<div class="strip">',
    ]
    for picture in strip:
        out.append(
            f"<figure>{_img(picture, f'camera at {clock(picture.time, zone)}')}"
            f"<figcaption>{_e(clock(picture.time, zone))} {_e(picture.stream)}</figcaption>"
            "</figure>"
        )
    out.append("</div>")
    out.append('<div class="timeline">')

    def tick(t: float, kind: str) -> str:
        left = 100.0 * (t - first) / span if span else 0.0
        return f'<span class="tick-{kind}" style="left:{min(max(left, 0.0), 99.8):.2f}%"></span>'

    out.extend(tick(float(row[0]), "picture") for row in choice.times.rows())
    out.extend(tick(float(f["time"]), str(f["verdict"])) for f in findings)
    out.append("</div>")
    if not findings:
        out.append('<p class="empty">no command judged not obeyed or partly obeyed</p>')
        return "\n".join(out)
    out.append(
        '<p class="small">For each command: the last picture before it was sent, and the '
        "one nearest to the moment its verdict was decided (the feedback that decided it). "
        "Findings about the feedback link as a whole have no picture.</p>"
    )
    out.append('<div class="seen">')
    for finding in findings:
        t = float(finding["time"])
        moment = verdict_moment(finding)
        before = choice.get(before_command(finding))
        wanted_after = at_verdict(finding)
        after = choice.get(wanted_after) if wanted_after is not None else None
        verdict = str(finding["verdict"])
        decided = ""
        if moment is not None:
            decided = f'<br><span class="small">decided at {_e(clock(moment, zone))}</span>'
        out.append(_figure(before, "before the command", t, zone))
        if moment is None:
            out.append('<figure><p class="empty">no moment of decision</p></figure>')
        else:
            out.append(_figure(after, "at the verdict", moment, zone))
        out.append(
            f"<div><b>{_e(clock(t, zone))} {_e(finding.get('command', ''))}</b>: "
            f'<span class="v v-{_e(verdict)}">{_e(verdict.replace("_", " "))}</span> '
            f"{_e(finding.get('detail', ''))}" + decided + "</div>"
        )
    out.append("</div>")
    return "\n".join(out)
