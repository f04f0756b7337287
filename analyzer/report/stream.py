"""The report's place in the pipeline: a sink for decoded events, a stage for findings."""

from __future__ import annotations

from collections.abc import Callable

from analyzer.pipeline import Batch, Stage
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, Event
from analyzer.report.collect import ReportData


class EventsInto:
    """A sink handing every decoded event to ``add`` (findings stored in the input are left
    out: the report judges the commands afresh, with its own settings)."""

    keeps_items = False  # only events are looked at

    def __init__(self, add: Callable[[Event], None]) -> None:
        self.add = add

    def handle(self, batch: Batch) -> None:
        add = self.add
        for event in batch.events:
            if event.topic != TOPIC_ANALYSIS_RESPONSE:
                add(event)

    def close(self) -> None:
        pass


class FindingsInto:
    """A pipeline stage around the response analysis, handing each finding to the report
    as it is made (nothing is kept: the report holds bounded summaries)."""

    def __init__(self, analysis: Stage, data: ReportData) -> None:
        self.analysis = analysis
        self.data = data

    def process(self, events: list[Event]) -> list[Event]:
        return self._hand_on(self.analysis.process(events))

    def close(self) -> list[Event]:
        return self._hand_on(self.analysis.close())

    def _hand_on(self, found: list[Event]) -> list[Event]:
        for finding in found:
            self.data.add_finding(finding.to_dict())
        return found
