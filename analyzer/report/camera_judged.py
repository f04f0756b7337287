"""The report's section on camera commands judged from the video: each with its two frames."""

from __future__ import annotations

import base64
import html
from collections.abc import Mapping, Sequence
from typing import Any

from analyzer.report.tables import clock
from analyzer.timefmt import UTC, TimeZone

CSS = """
.judged { display: grid; grid-template-columns: 240px 240px 1fr; gap: 8px 14px;
          align-items: start; margin-top: 6px; }
.judged img { width: 240px; display: block; border-radius: 2px; }
.judged figure { margin: 0; }
"""


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _frame(
    jpeg: bytes | None, what: str, t: float | None, command_time: float, zone: TimeZone
) -> str:
    if jpeg is None or t is None:
        return f'<figure><p class="empty">no frame {_e(what)}</p></figure>'
    data = base64.b64encode(jpeg).decode("ascii")
    return (
        f'<figure><img src="data:image/jpeg;base64,{data}" alt="{_e(what)}">'
        f"<figcaption>{_e(what)}: {_e(clock(t, zone))} ({t - command_time:+.2f} s)</figcaption>"
        "</figure>"
    )


def judged_section(
    findings: Sequence[Mapping[str, Any]],
    pictures: Mapping[tuple[str, float], bytes],
    zone: TimeZone = UTC,
) -> str:
    """The HTML of "Camera commands judged from the video" (empty without such findings),
    its times in ``zone``."""
    if not findings:
        return ""
    out = [
        '<h2 id="camera-judged">Camera commands judged from the video</h2>',
        '<p class="small">The feedback does not report the zoom, the palette or the '
        "picture-in-picture layout: these commands are judged from the recorded video, the "
        "frame before each command against the one after it settled. Scale: the picture's "
        "change of scale (> 1 zoomed in), what the aircraft's motion explains taken out.</p>",
        '<div class="judged">',
    ]
    for finding in findings:
        t = float(finding["time"])
        stream = str(finding.get("stream", ""))
        before, after = finding.get("frame_before"), finding.get("frame_after")
        verdict = str(finding["verdict"])
        for what, moment in (("before", before), ("after", after)):
            jpeg = pictures.get((stream, round(float(moment), 3))) if moment else None
            out.append(_frame(jpeg, what, moment, t, zone))
        scale = finding.get("scale")
        numbers = f" scale x{scale:.3g}" if isinstance(scale, (int, float)) else ""
        where = f" on /camera/{stream}" if stream else ""
        out.append(
            f"<div><b>{_e(clock(t, zone))} {_e(finding.get('command', ''))}</b>{_e(where)}: "
            f'<span class="v v-{_e(verdict)}">{_e(verdict.replace("_", " "))}</span>'
            f"{_e(numbers)}<br>{_e(finding.get('detail', ''))}</div>"
        )
    out.append("</div>")
    return "\n".join(out)
