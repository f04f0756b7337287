"""The monitor's demo screen: the text the manual shows, and Textual's own SVG of it."""

from __future__ import annotations

from pathlib import Path

import pytest

from analyzer.tui.demo_screen import main


@pytest.mark.slow
def test_the_demo_screen_prints_the_monitor_and_writes_its_picture(
    tmp_path: Path, capsys: object
) -> None:
    picture = tmp_path / "monitor.svg"
    assert main(["120", "38", "--svg", str(picture)]) == 0
    text = capsys.readouterr().out  # type: ignore[attr-defined]
    assert "Gimbal" in text and "CAN IDs" in text and "Diagnostics" in text
    svg = picture.read_text(encoding="utf-8").replace("&#160;", " ")
    assert svg.startswith("<svg") and "gimbal-analyzer monitor" in svg
    assert "feedback" in svg and "0x030F0001" in svg
