"""The stages every command that records or shows events runs: the response analysis."""

from __future__ import annotations

from analyzer.analysis.response import ResponseAnalyzer, Settings
from analyzer.pipeline import Stage


def analysis_stages(settings: Settings | None = None) -> list[Stage]:
    """The stages of record, demo, monitor and convert (a ResponseAnalyzer is a Stage)."""
    return [ResponseAnalyzer(settings)]
