"""The report's camera section: thumbnails along the timeline and next to failed commands."""

from __future__ import annotations

import base64
import bisect
import html
from collections.abc import Sequence
from typing import Any, Protocol

from analyzer import timefmt

STRIP_SIZE = 8  # thumbnails in the strip along the timeline
MAX_FINDING_PICTURES = 40
SHOWN_VERDICTS = ("not_obeyed", "partial")

CSS = """
.strip { display: flex; gap: 4px; margin: 6px 0 2px; }
.strip figure, .seen figure { margin: 0; flex: 1 1 0; min-width: 0; }
.strip img { width: 100%; display: block; border-radius: 2px; }
figcaption { font-size: 11px; color: #555; }
.timeline { position: relative; height: 14px; background: #f0f0f0; margin: 2px 0 16px; }
.timeline span { position: absolute; top: 0; width: 2px; height: 14px; }
.tick-picture { background: #4e98e2; } .tick-not_obeyed { background: #d62728; }
.tick-partial { background: #ff9800; }
.seen { display: grid; grid-template-columns: 240px 1fr; gap: 6px 14px; align-items: start; }
.seen img { width: 240px; display: block; border-radius: 2px; }
"""


class Picture(Protocol):
    """A thumbnail of a camera stream (``analyzer.mcapio.read.video.Thumbnail``)."""

    stream: str
    time: float
    jpeg: bytes


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _clock(t: float) -> str:
    return timefmt.format_clock(t) if timefmt.is_absolute(t) else f"{t:.3f} s"


def _img(picture: Picture, alt: str) -> str:
    data = base64.b64encode(picture.jpeg).decode("ascii")
    return f'<img src="data:image/jpeg;base64,{data}" alt="{_e(alt)}">'


def nearest(pictures: Sequence[Picture], times: list[float], t: float) -> Picture:
    """The picture taken nearest to ``t`` (``times`` are the pictures' times, sorted)."""
    i = bisect.bisect_left(times, t)
    candidates = [j for j in (i - 1, i) if 0 <= j < len(pictures)]
    return pictures[min(candidates, key=lambda j: abs(times[j] - t))]


def camera_section(pictures: Sequence[Picture], findings: list[dict[str, Any]]) -> str:
    """The HTML of "What the camera saw" (empty when the input has no camera thumbnails)."""
    if not pictures:
        return ""
    shown = sorted(pictures, key=lambda p: p.time)
    times = [p.time for p in shown]
    first, last = times[0], times[-1]
    span = last - first
    strip_at = [first + span * i / (STRIP_SIZE - 1) for i in range(STRIP_SIZE)] if span else [first]
    strip: list[Picture] = []
    for t in strip_at:
        picture = nearest(shown, times, t)
        if picture not in strip:
            strip.append(picture)
    failed = [f for f in findings if str(f.get("verdict")) in SHOWN_VERDICTS]
    failed.sort(key=lambda f: float(f["time"]))
    streams = ", ".join(sorted({p.stream for p in shown}))
    out = [
        "<h2>What the camera saw</h2>",
        f'<p class="small">{len(shown)} thumbnails of {_e(streams)}'
        f" from {_e(_clock(first))} to {_e(_clock(last))}. Blue ticks: thumbnails; red and "
        "orange: commands not obeyed / partly obeyed.</p>",
        '<div class="strip">',
    ]
    for picture in strip:
        out.append(
            f"<figure>{_img(picture, f'camera at {_clock(picture.time)}')}"
            f"<figcaption>{_e(_clock(picture.time))} {_e(picture.stream)}</figcaption></figure>"
        )
    out.append("</div>")
    out.append('<div class="timeline">')

    def tick(t: float, kind: str) -> str:
        left = 100.0 * (t - first) / span if span else 0.0
        return f'<span class="tick-{kind}" style="left:{min(max(left, 0.0), 99.8):.2f}%"></span>'

    out.extend(tick(p.time, "picture") for p in shown)
    out.extend(tick(float(f["time"]), str(f["verdict"])) for f in failed)
    out.append("</div>")
    if not failed:
        out.append('<p class="empty">every judged command was obeyed</p>')
        return "\n".join(out)
    out.append('<div class="seen">')
    for finding in failed[:MAX_FINDING_PICTURES]:
        t = float(finding["time"])
        picture = nearest(shown, times, t)
        offset = picture.time - t
        verdict = str(finding["verdict"]).replace("_", " ")
        out.append(
            f"<figure>{_img(picture, f'camera near {_clock(t)}')}</figure>"
            f"<div><b>{_e(_clock(t))} {_e(finding.get('command', ''))}</b>: "
            f'<span class="v v-{_e(finding["verdict"])}">{_e(verdict)}</span> '
            f"{_e(finding.get('detail', ''))}<br>"
            f'<span class="small">picture of {_e(picture.stream)} at {_e(_clock(picture.time))} '
            f"({offset:+.1f} s from the command)</span></div>"
        )
    out.append("</div>")
    if len(failed) > MAX_FINDING_PICTURES:
        out.append(f'<p class="small">the first {MAX_FINDING_PICTURES} are shown</p>')
    return "\n".join(out)
