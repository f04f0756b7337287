"""convert_items: the decode-and-write loop of `convert`, independent of the file readers."""

from __future__ import annotations

from pathlib import Path

from analyzer.mcapio.convert import convert_items
from analyzer.mcapio.reader import read_events, read_items
from analyzer.mcapio.writer import McapSink
from analyzer.protocol.types import BAD_LINE, diagnostic
from tests.test_mcap_support import decode_all, event_dicts, traffic


def test_items_and_passed_through_events_are_written(tmp_path: Path) -> None:
    path = tmp_path / "out.mcap"
    items = traffic(30.0)
    bad = diagnostic(items[3].time, "log", BAD_LINE, "line 4: not a candump line", b"??")
    stream = [*items[:3], bad, *items[3:]]
    seen: list[int] = []
    sink = McapSink(path, metadata={"source": "t"}, flush_interval=None)
    result = convert_items(stream, sink, progress=lambda r: seen.append(r.items))
    sink.close()
    assert result.items == len(items)
    assert result.frames + result.chunks == len(items)
    assert result.messages == sink.messages_written
    assert seen and seen[-1] == len(items) and seen == sorted(seen)
    assert list(read_items(path)) == items
    stored = event_dicts(list(read_events(path)))
    # in time order: a diagnostic found late (end of input) comes back in its place
    expected = event_dicts(sorted(decode_all(items), key=lambda e: e.time))
    assert [e for e in stored if e.get("kind") != BAD_LINE] == expected
    assert [e["detail"] for e in stored if e.get("kind") == BAD_LINE] == [bad.fields["detail"]]
    assert result.events == len(stored)
