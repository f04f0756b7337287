"""Per-source decoder state is bounded; what is given up is reported, never dropped silently."""

from __future__ import annotations

import tracemalloc

from analyzer.feedback_track import MAX_FEEDBACK_SOURCES
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.ids import FEEDBACK_ID, TEXT_ID
from analyzer.protocol.lru import MAX_SOURCES, LruTable
from analyzer.protocol.types import (
    INCOMPLETE,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_UAV_TEXT,
    CanFrame,
    Event,
    StreamChunk,
)
from analyzer.protocol.uav import encode_text
from analyzer.summary import Summary

MESSAGE = encode_attitude(pitch_deg=-10.0, yaw_deg=20.0)
SEGMENTS = segments(MESSAGE)


def _given_up(events: list[Event]) -> list[Event]:
    return [
        e
        for e in events
        if e.topic == TOPIC_DIAGNOSTICS and "given up early" in str(e.fields.get("detail"))
    ]


def test_lru_table_evicts_the_least_recently_used() -> None:
    evicted: list[tuple[str, int]] = []
    table: LruTable[str, int] = LruTable(lambda k, v: evicted.append((k, v)), limit=2)
    table.add("a", 1)
    table.add("b", 2)
    assert table.get("a") == 1  # a is now the most recently used
    table.add("c", 3)
    assert evicted == [("b", 2)] and table.evicted == 1
    assert sorted(table.values()) == [1, 3] and len(table) == 2


def test_partial_feedback_of_evicted_channels_is_reported_with_the_reason() -> None:
    decoder = ProtocolDecoder(max_sources=4)
    events: list[Event] = []
    for i in range(10):  # half a message on each of 10 channels
        for n, segment in enumerate(SEGMENTS[:2]):
            events += decoder.feed_can(CanFrame(1.0 + i * 0.01 + n * 0.001, FEEDBACK_ID, segment,
                                                channel=f"ch{i}"))  # fmt: skip
    assert len(decoder._reassemblers) == 4
    given_up = _given_up(events)
    assert [e.source for e in given_up] == [f"ch{i}" for i in range(6)]
    assert all(e.fields["kind"] == INCOMPLETE for e in given_up)
    assert "more than 4 sources at once" in given_up[0].fields["detail"]
    end = decoder.close()
    assert sorted(e.source for e in end) == [f"ch{i}" for i in range(6, 10)]
    stats = decoder.stats
    assert stats["sources_given_up"] == 6
    assert stats["bytes_fed"] == 10 * 16 == stats["bytes_discarded"]  # nothing uncounted


def test_a_busy_channel_keeps_its_state_among_many_one_shot_channels() -> None:
    decoder = ProtocolDecoder(max_sources=8)
    attitudes = 0
    t = 1.0
    for round_ in range(50):
        for segment in SEGMENTS:
            t += 0.001
            for event in decoder.feed_can(CanFrame(t, FEEDBACK_ID, segment, channel="can0")):
                attitudes += event.topic == TOPIC_GIMBAL_ATTITUDE
            # between every two segments of can0, a stranger on a new channel
            decoder.feed_can(CanFrame(t, FEEDBACK_ID, SEGMENTS[1], channel=f"x{round_}-{t}"))
    assert attitudes == 50
    assert decoder.stats["sources_given_up"] > 0


def test_text_and_stream_state_are_bounded_too() -> None:
    decoder = ProtocolDecoder(max_sources=3)
    events: list[Event] = []
    first_text = encode_text("HELLO WORLD")[0]  # a start frame, never ended
    for i in range(6):
        events += decoder.feed_can(CanFrame(1.0, TEXT_ID, first_text[1], channel=f"t{i}"))
        half = wrap_control(bytes(8))[:10]
        events += decoder.feed_stream(StreamChunk(1.0, half, f"tcp:{i}", "gs_to_idu"))
    assert len(decoder._texts) == 3 and len(decoder._framers) == 3
    sources = sorted(e.source for e in _given_up(events))
    assert sources == sorted([f"t{i}" for i in range(3)] + [f"tcp:{i}" for i in range(3)])
    assert decoder.stats["bytes_fed"] == 6 * 10
    events += decoder.close()
    assert not [e for e in events if e.topic == TOPIC_UAV_TEXT]


def test_a_million_channel_names_cannot_grow_the_decoder() -> None:
    decoder = ProtocolDecoder()
    count = MAX_SOURCES * 8
    tracemalloc.start()
    for i in range(count // 2):
        decoder.feed_can(CanFrame(1.0 + i * 1e-4, FEEDBACK_ID, SEGMENTS[0], channel=f"c{i}"))
    half_way = tracemalloc.get_traced_memory()[0]
    for i in range(count // 2, count):
        decoder.feed_can(CanFrame(1.0 + i * 1e-4, FEEDBACK_ID, SEGMENTS[0], channel=f"c{i}"))
    full = tracemalloc.get_traced_memory()[0]
    tracemalloc.stop()
    assert len(decoder._reassemblers) == MAX_SOURCES
    assert full - half_way < 256 * 1024  # flat once the table is full
    assert decoder.stats["sources_given_up"] == count - MAX_SOURCES


def test_summary_tracks_feedback_of_a_bounded_number_of_sources() -> None:
    summary = Summary("x.log", "candump")
    extra = 5
    for i in range(MAX_FEEDBACK_SOURCES + extra):
        fields = {"pitch_deg": 0.0}
        summary.add(Event(TOPIC_GIMBAL_ATTITUDE, 1.0 + i, f"c{i}", fields))
    assert len(summary.feedback) == MAX_FEEDBACK_SOURCES
    assert summary.tally.feedback_untracked == extra
    assert summary.crc_checked == MAX_FEEDBACK_SOURCES + extra  # still counted
    assert f"{extra} more feedback messages from streams beyond" in summary.render()
    again = type(summary.tally).from_metadata(summary.tally.to_metadata())  # as recorded
    assert again.feedback_untracked == extra
    summary.finish(decoder_stats={"sources_given_up": 7})
    assert "7 sources' decoder state given up early" in summary.render()
