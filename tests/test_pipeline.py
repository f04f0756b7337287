"""The pipeline every command runs: decode, stages, one tally, sinks; and its file driver."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from analyzer.mcapio.read.reader import read_events, read_items
from analyzer.mcapio.write.sink import McapSink
from analyzer.pipeline import Batch, Pipeline, run_items, run_reader
from analyzer.protocol.types import BAD_LINE, TOPIC_COMMAND, Event, diagnostic
from tests.test_mcap_support import decode_all, event_dicts, traffic


class Collect:
    def __init__(self) -> None:
        self.batches: list[Batch] = []
        self.closed = False

    def handle(self, batch: Batch) -> None:
        self.batches.append(batch)

    def close(self) -> None:
        self.closed = True


class CountCommands:
    """A stage: one finding per batch that held commands, one more at the end."""

    def __init__(self) -> None:
        self.seen = 0

    def process(self, events: list[Event]) -> list[Event]:
        commands = [e for e in events if e.topic == TOPIC_COMMAND]
        self.seen += len(commands)
        if not commands:
            return []
        return [Event("/analysis/finding", commands[-1].time, "test", {"n": len(commands)})]

    def close(self) -> list[Event]:
        return [Event("/analysis/finding", 0.0, "test", {"total": self.seen})]


class Broken:
    def handle(self, batch: Batch) -> None:
        raise OSError(28, "No space left on device")

    def close(self) -> None:
        pass


def test_items_and_passed_through_events_are_written(tmp_path: Path) -> None:
    path = tmp_path / "out.mcap"
    items = traffic(30.0)
    bad = diagnostic(items[3].time, "log", BAD_LINE, "line 4: not a candump line", b"??")
    stream = [*items[:3], bad, *items[3:]]
    seen: list[int] = []
    sink = McapSink(path, metadata={"source": "t"}, flush_interval=None)
    pipeline = Pipeline([sink])
    run_items(
        stream,
        pipeline,
        batch_items=100,
        after_batch=lambda b: seen.append(pipeline.tally.frames + pipeline.tally.chunks),
    )
    assert sink.closed
    tally = pipeline.tally
    assert tally.frames + tally.chunks == len(items)
    assert seen and seen[-1] == len(items) and seen == sorted(seen)
    assert list(read_items(path)) == items
    stored = event_dicts(list(read_events(path)))
    # in time order: a diagnostic found late (end of input) comes back in its place
    expected = event_dicts(sorted(decode_all(items), key=lambda e: e.time))
    assert [e for e in stored if e.get("kind") != BAD_LINE] == expected
    assert [e["detail"] for e in stored if e.get("kind") == BAD_LINE] == [bad.fields["detail"]]
    assert tally.events == len(stored)
    # The sink counted what it wrote with the same tally as the pipeline.
    assert sink.tally.figures() == tally.figures()


def test_a_stage_adds_events_that_sinks_and_tally_see() -> None:
    items = traffic(10.0)
    sink = Collect()
    stage = CountCommands()
    pipeline = Pipeline([sink], stages=[stage])
    run_items(items, pipeline, batch_items=50)
    events = [e for b in sink.batches for e in b.events]
    findings = [e for e in events if e.topic == "/analysis/finding"]
    commands = sum(1 for e in events if e.topic == TOPIC_COMMAND)
    assert commands and stage.seen == commands
    assert findings[-1].fields == {"total": commands}
    assert sum(f.fields.get("n", 0) for f in findings) == commands
    assert pipeline.tally.topics["/analysis/finding"] == len(findings)
    assert pipeline.tally.events == len(events)
    assert sink.closed


def test_a_failing_sink_stops_the_file_run_and_the_others_are_closed() -> None:
    good = Collect()
    broken = Broken()
    pipeline = Pipeline([broken, good])
    run_items(traffic(30.0), pipeline, batch_items=10)
    assert len(pipeline.failures) == 1
    assert pipeline.failures[0].sink is broken
    assert isinstance(pipeline.failures[0].error, OSError)
    assert good.closed and len(good.batches) == 2  # the first batch and the last one


def test_an_interrupt_leaves_finishing_to_the_caller_and_finish_runs_once() -> None:
    sink = Collect()
    pipeline = Pipeline([sink])

    def items() -> Iterator[Any]:
        yield from traffic(2.0)[:5]
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_items(items(), pipeline, batch_items=1)
    assert not sink.closed and not pipeline.finished
    pipeline.finish()
    assert sink.closed and pipeline.finished
    assert pipeline.tally.frames + pipeline.tally.chunks == 5
    pipeline.finish()
    assert pipeline.tally.frames + pipeline.tally.chunks == 5


class Reader:
    """A file reader: its items, then ``KeyboardInterrupt`` if ``interrupt``; notes its close."""

    def __init__(self, items: list[Any], *, interrupt: bool = False) -> None:
        self.items, self.interrupt, self.closed = items, interrupt, False

    def __iter__(self) -> Iterator[Any]:
        yield from self.items
        if self.interrupt:
            raise KeyboardInterrupt

    def close(self) -> None:
        self.closed = True


def test_a_file_run_closes_its_reader_and_raises_what_a_sink_raised() -> None:
    reader, good = Reader(traffic(5.0)), Collect()
    with pytest.raises(OSError, match="No space left"):
        run_reader(reader, Pipeline([Broken(), good]), batch_items=10)
    assert reader.closed and good.closed


def test_ctrl_c_ends_a_live_input_as_its_end_would_and_a_file_run_propagates_it() -> None:
    items = traffic(2.0)[:5]
    live, sink = Reader(items, interrupt=True), Collect()
    pipeline = Pipeline([sink])
    assert run_reader(live, pipeline, batch_items=1, interruptible=True) is True
    assert live.closed and sink.closed and pipeline.tally.frames + pipeline.tally.chunks == 5
    file = Reader(items, interrupt=True)
    with pytest.raises(KeyboardInterrupt):
        run_reader(file, Pipeline([Collect()]))
    assert file.closed
    assert run_reader(Reader(items), Pipeline()) is False


def test_the_response_analyzer_is_a_stage_and_analyze_runs_it_in_the_pipeline(
    capsys: pytest.CaptureFixture[str],
) -> None:
    from analyzer.analysis.response import ResponseAnalyzer
    from analyzer.cli import main
    from analyzer.inputs import open_input
    from analyzer.protocol.ids import PROTOCOL_IDS
    from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE

    sample = str(Path(__file__).resolve().parent.parent / "samples" / "flight-candump.log")
    sink = Collect()
    pipeline = Pipeline([sink], stages=[ResponseAnalyzer()])
    run_items(open_input(sample, None, 2000, wanted_ids=PROTOCOL_IDS), pipeline)
    found = [e for b in sink.batches for e in b.events if e.topic == TOPIC_ANALYSIS_RESPONSE]
    assert found  # the findings reach the sinks, but as judgements they are not counted
    assert TOPIC_ANALYSIS_RESPONSE not in pipeline.tally.topics
    assert main(["analyze", sample, "--json"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(found)


class Watch:
    """A stage noting what it saw, and whether it had closed when it saw it."""

    def __init__(self) -> None:
        self.closed = False
        self.after_close: list[str] = []
        self.kinds: list[str] = []

    def process(self, events: list[Event]) -> list[Event]:
        kinds = [str(e.fields["kind"]) for e in events if e.topic == "/diagnostics"]
        self.kinds += kinds
        if self.closed:
            self.after_close += kinds
        return []

    def close(self) -> list[Event]:
        self.closed = True
        return []


def test_the_stages_see_what_the_decoder_says_at_the_end_before_they_close() -> None:
    from analyzer.protocol.feedback import encode_attitude, segments
    from analyzer.protocol.ids import FEEDBACK_ID
    from analyzer.protocol.types import CanFrame

    cut = [CanFrame(1.0, FEEDBACK_ID, part, channel="can0") for part in segments(
        encode_attitude(pitch_deg=1, yaw_deg=2))[:3]]  # fmt: skip
    watch = Watch()
    pipeline = Pipeline(stages=[watch])
    run_items(cut, pipeline)
    # the message the input cut short is reported by the decoder's close(): the stage
    # (the response analysis counts damaged feedback) hears of it while still open
    assert watch.kinds == ["incomplete"] and watch.after_close == [] and watch.closed
