"""The figures a recording keeps are the pipeline's: counted once per batch, not twice."""

from __future__ import annotations

from pathlib import Path

import pytest

from analyzer.analysis.stage import Analysis
from analyzer.mcapio.read.info import recording_info
from analyzer.mcapio.write.sink import McapSink
from analyzer.pipeline import Pipeline, run_items
from analyzer.protocol.types import CanFrame
from analyzer.tally import Tally
from tests.test_mcap_support import T0, traffic


def _convert(path: Path, flush_interval: float | None) -> tuple[Pipeline, McapSink]:
    sink = McapSink(path, metadata={"source": "test"}, flush_interval=flush_interval)
    pipeline = Pipeline(sinks=[sink], stages=Analysis().stages())
    run_items(traffic(6.0, gap_after=2.0, bus_off=True), pipeline, batch_items=7)
    return pipeline, sink


def test_a_file_conversion_counts_each_batch_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls = {"items": 0, "events": 0}
    add_items, add_events = Tally.add_items, Tally.add_events

    def counting_items(self: Tally, items: list[CanFrame]) -> None:
        calls["items"] += 1
        add_items(self, items)

    def counting_events(self: Tally, events: list[object]) -> None:
        calls["events"] += 1
        add_events(self, events)  # type: ignore[arg-type]

    monkeypatch.setattr(Tally, "add_items", counting_items)
    monkeypatch.setattr(Tally, "add_events", counting_events)
    pipeline, sink = _convert(tmp_path / "flight.mcap", flush_interval=None)
    assert sink.tally is pipeline.tally
    assert calls == {"items": pipeline.delivered, "events": pipeline.delivered}
    # The record in the file is what the pipeline counted, and what a scan finds.
    info = recording_info(tmp_path / "flight.mcap")
    assert info.tally.figures() == pipeline.tally.figures()
    assert info.tally.items() == pipeline.tally.items()
    scanned = recording_info(tmp_path / "flight.mcap", scan=True)
    assert scanned.tally.figures() == info.tally.figures()


def test_a_live_recording_counts_for_itself(tmp_path: Path) -> None:
    """Its flush thread may read the figures while the capture thread counts: the sink keeps
    its own, equal to the pipeline's."""
    pipeline, sink = _convert(tmp_path / "live.mcap", flush_interval=0.05)
    assert sink.tally is not pipeline.tally
    assert sink.tally.figures() == pipeline.tally.figures()
    assert recording_info(tmp_path / "live.mcap").tally.figures() == pipeline.tally.figures()


def test_a_sink_that_joins_late_counts_for_itself(tmp_path: Path) -> None:
    """The pipeline's figures would include batches it never wrote."""
    items = traffic(3.0)
    late = Pipeline()
    late.feed(items[20:40])
    late.deliver()
    sink = McapSink(tmp_path / "late.mcap", metadata={"source": "test"}, flush_interval=None)
    late.sinks.append(sink)
    late.feed(items[40:])
    late.finish()
    assert sink.tally is not late.tally
    assert sink.tally.frames == sum(1 for i in items[40:] if isinstance(i, CanFrame))


def test_a_message_written_outside_the_batches_is_not_added_to_the_pipeline(
    tmp_path: Path,
) -> None:
    sink = McapSink(tmp_path / "extra.mcap", metadata={"source": "test"}, flush_interval=None)
    pipeline = Pipeline(sinks=[sink])
    pipeline.feed(traffic(2.0))
    pipeline.deliver()
    assert sink.tally is pipeline.tally
    frames = pipeline.tally.frames
    sink.write_item(CanFrame(T0 + 5.0, 0x0F01, bytes(8)))
    assert pipeline.tally.frames == frames  # the pipeline never saw it
    assert sink.tally.frames == frames + 1
    pipeline.finish()
    assert recording_info(tmp_path / "extra.mcap").tally.frames == frames + 1
