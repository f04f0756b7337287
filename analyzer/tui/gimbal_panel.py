"""Gimbal state panel: attitude gauges, type and mode, last camera commands, feedback age."""

from __future__ import annotations

from rich.text import Text

from analyzer.protocol.feedback import (
    MOTOR_YAW_LIMIT,
    WIDE_MOTOR_YAW_LIMIT,
    WIDE_MOTOR_YAW_TYPES,
)
from analyzer.protocol.types import Event
from analyzer.tui.fit import grid, join_lines, pack
from analyzer.tui.fitted_panel import FittedPanel
from analyzer.tui.formatting import (
    compass,
    describe_params,
    format_age,
    labelled,
    short_age,
    value_bar,
)
from analyzer.tui.state import MonitorState

PITCH_RANGE = (-110.0, 60.0)
YAW_RANGE = (0.0, 360.0)
MOTOR_YAW_RANGE = (-MOTOR_YAW_LIMIT / 100, MOTOR_YAW_LIMIT / 100)
WIDE_MOTOR_YAW_RANGE = (-WIDE_MOTOR_YAW_LIMIT / 100, WIDE_MOTOR_YAW_LIMIT / 100)  # 3.5x zoom
BAR_WIDTH = 22
MIN_BAR_WIDTH = 8


def _axis(
    label: str, value: float | None, low: float, high: float, width: int, note: str = ""
) -> Text:
    """'pitch  -37.25°  [---o--|---] -110..60': the gauge shrinks (or goes) on narrow panels."""
    line = Text(f"{label:<10}")
    line.append("     —  " if value is None else f"{value:8.2f}°", style="bold")
    if note:
        line.append(f" {note:<2}", style="bold")
    limits = f" {low:g}..{high:g}"
    bar = min(BAR_WIDTH, width - line.cell_len - 2 - len(limits))
    if bar >= MIN_BAR_WIDTH:
        line.append("  ")
        line.append(value_bar(value, low, high, bar), style="cyan")
        line.append(limits, style="dim")
    return line


def _command_cell(state: MonitorState, label: str, event: Event | None) -> Text:
    """'zoom  zoom_in  0.25s': label, what was asked (in full), how long ago."""
    cell = Text(f"{label:<6}", style="dim")
    if event is None:
        cell.append("—")
        return cell
    name = str(event.fields.get("name", ""))
    params = describe_params(event)
    summary = f"{name} {params}".strip() if label == "move" else params or name
    cell.append(summary, style="bold")
    cell.append(f"  {short_age(state.age(event))}", style="dim")
    return cell


def gimbal_lines(state: MonitorState, width: int) -> list[Text]:
    """The panel's lines at ``width`` cells: every value in full, more lines when narrow."""
    att = state.attitude
    f = att.fields if att is not None else {}
    pitch = f.get("pitch_deg")
    yaw = f.get("yaw_deg")
    motor = f.get("motor_yaw_deg")
    type_label, type_code = labelled(f, "gimbal_type")
    motor_range = WIDE_MOTOR_YAW_RANGE if type_code in WIDE_MOTOR_YAW_TYPES else MOTOR_YAW_RANGE
    lines = [
        _axis("pitch", pitch, *PITCH_RANGE, width),
        _axis("yaw", yaw, *YAW_RANGE, width, note=compass(yaw) if yaw is not None else ""),
        _axis("motor yaw", motor, *motor_range, width),
    ]
    if att is None:
        lines.append(Text("mode —  tracking —  type —", style="dim"))
    else:
        tracking = bool(f.get("tracking"))
        mode = Text.assemble(("mode ", "dim"), (labelled(f, "control_mode")[0], "bold"))
        track = Text.assemble(
            ("tracking ", "dim"),
            ("YES" if tracking else "no", "bold green" if tracking else "bold"),
        )
        kind = Text.assemble(("type ", "dim"), (type_label, "bold"))
        if type_code is not None:
            kind.append(f" ({type_code})", style="dim")
        lines += pack([mode, track, kind], width, indent=2)
    cmds = state.last_commands
    cells = [
        _command_cell(state, label, cmds.get(group))
        for label, group in (
            ("zoom", "zoom"),
            ("focus", "focus"),
            ("rec", "recording"),
            ("snap", "snapshot"),
            ("move", "motion"),
        )
    ]
    lines += grid(cells, width)
    age = state.feedback_age
    stale = state.feedback_stale
    feedback = Text("feedback ", style="dim")
    feedback.append(
        f"{format_age(age)} ago" if age is not None else "none yet",
        style="bold white on red" if stale else "bold green",
    )
    rate = state.feedback_rate
    cells = [
        feedback,
        Text(f"{rate:.1f}/s", style="bold"),
        Text(f"{state.feedback_count:,} messages", style="dim"),
    ]
    if state.ranging is not None:
        rf = state.ranging.fields
        ranging = Text("ranging ", style="dim")
        if rf.get("success", True):
            ranging.append(f"{rf.get('distance_m', 0):.1f} m")
        else:
            ranging.append("no target")
        cells.append(ranging)
    lines += pack(cells, width, indent=2)
    return lines


def render_gimbal(state: MonitorState, width: int = 76) -> Text:
    """The panel's text at ``width`` cells (also used by tests)."""
    return join_lines(gimbal_lines(state, width))


class GimbalPanel(FittedPanel):
    """Redrawn from the state at the app's refresh rate."""

    def on_mount(self) -> None:
        self.border_title = "Gimbal"

    def lines(self, state: MonitorState, width: int) -> list[Text]:
        return gimbal_lines(state, width)
