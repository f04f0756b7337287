"""Every short way of the hot path gives what the long way gives, for any input.

The decoder's batch loop (every kind of item in one loop, counted once), the feedback
reassembler's usual case and the counters' batch folding exist only for speed; these
properties hold them to the plain code they stand in for.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.feedback_track import FeedbackClock, FeedbackTrack
from analyzer.protocol.codec import encode_command
from analyzer.protocol.crc import crc_bytes
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, encode_ranging, segments
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.reassembly import FeedbackReassembler, Message
from analyzer.protocol.types import (
    CRC_MISMATCH,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_GPS,
    CanFrame,
    Event,
    StreamChunk,
)
from analyzer.protocol.uav import encode_gps
from analyzer.tally import CAN_BITS_EXTENDED, CAN_BITS_STANDARD, Tally

pytestmark = pytest.mark.slow  # long property runs

ATTITUDE = encode_attitude(pitch_deg=-30, yaw_deg=12, motor_yaw_deg=0)
RANGING = encode_ranging(distance_m=150, height_m=80, latitude_deg=31.1, longitude_deg=118.1)
# A message whose last segment starts like a header (EB 90 10): what is a repeat of it?
TRICKY = RANGING[:24] + b"\xeb\x90\x10\x00\x00" + RANGING[29:]
TRICKY = TRICKY[:29] + crc_bytes(TRICKY[:29]) + b"\x00"
MESSAGES = [ATTITUDE, RANGING, TRICKY]
SEGMENTS = [part for message in MESSAGES for part in segments(message)]
PAYLOADS = [
    *SEGMENTS,
    encode_command("gimbal_control", pan_speed_dps=5, tilt_speed_dps=-2),
    encode_command("zoom", action="zoom_in"),
    bytes.fromhex("0F42000000000000"),
    encode_gps(31.12, 118.12),
    bytes.fromhex("FFFFFFFF7F000000"),
    b"HELLO",
    b"",
    bytes(12),
]
IDS = [CONTROL_ID, FEEDBACK_ID, GPS_ID, ALTITUDE_ID, UAV_ATTITUDE_ID, TEXT_ID, TEXT_END_ID, 0x123]


@st.composite
def frames(draw: st.DrawFn) -> CanFrame:
    return CanFrame(
        draw(st.floats(0, 100, allow_nan=False)),
        draw(st.sampled_from(IDS)),
        draw(st.sampled_from(PAYLOADS) | st.binary(max_size=8)),
        draw(st.booleans() | st.just(True)),
        draw(st.sampled_from(["can0", "can1", ""])),
        draw(st.booleans() if draw(st.integers(0, 9)) == 0 else st.just(False)),
        draw(st.booleans() if draw(st.integers(0, 9)) == 0 else st.just(False)),
        draw(st.booleans() if draw(st.integers(0, 9)) == 0 else st.just(False)),
    )


@st.composite
def feedback_runs(draw: st.DrawFn) -> list[CanFrame]:
    """The four segments of a message in a row (the usual case), on one channel."""
    message = draw(st.sampled_from(MESSAGES))
    start = draw(st.floats(0, 90))
    channel = draw(st.sampled_from(["can0", "can1"]))
    return [
        CanFrame(start + i * 0.001, FEEDBACK_ID, part, True, channel)
        for i, part in enumerate(segments(message))
    ]


items = st.lists(
    st.one_of(
        frames().map(lambda f: [f]),
        feedback_runs(),
        st.builds(StreamChunk, st.floats(0, 100), st.binary(max_size=30)).map(lambda c: [c]),
        st.builds(Event, st.just("/diagnostics"), st.floats(0, 100), st.just("f")).map(
            lambda e: [e]
        ),
    ),
    max_size=30,
).map(lambda runs: [item for run in runs for item in run])


def as_dicts(events: list[Event]) -> list[dict[str, Any]]:
    return [e.to_dict() for e in events]


@settings(max_examples=300, deadline=None)
@given(items, st.booleans(), st.integers(1, 4))
def test_feed_batch_is_the_general_path_item_by_item(
    batch: list[Any], other: bool, sources: int
) -> None:
    one = ProtocolDecoder(emit_other=other, max_sources=sources)
    slow: list[Event] = []
    for item in batch:
        if isinstance(item, CanFrame):  # the long way: the general path for every frame
            one.frames += 1
            one.last_time = item.time
            slow += one._frame(item, item.channel or "can", {})
        elif isinstance(item, StreamChunk):
            slow += one.feed_stream(item)
        else:
            slow.append(item)
    slow += one.close()
    two = ProtocolDecoder(emit_other=other, max_sources=sources)
    fast: list[Event] = []
    half = len(batch) // 2
    two.feed_batch(batch[:half], fast)
    two.feed_batch(batch[half:], fast)
    fast += two.close()
    assert as_dicts(fast) == as_dicts(slow)
    assert two.stats == one.stats
    assert two.last_time == one.last_time


def results(r: FeedbackReassembler, parts: list[tuple[bytes, float]]) -> list[Any]:
    out: list[Message | Event] = []
    for data, time in parts:
        out += r.feed(data, time)
        if time > 50:
            out += r.tick(time + 0.5)
    out += r.close(200.0)
    return [x if isinstance(x, Message) else x.to_dict() for x in out]


@settings(max_examples=500, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.tuples(
                st.sampled_from(SEGMENTS) | st.binary(max_size=9),
                st.floats(0, 0.3) | st.sampled_from([0.001, 1.5, 0.0]),
            ).map(lambda step: [step]),
            st.sampled_from(MESSAGES).map(lambda m: [(part, 0.001) for part in segments(m)]),
        ),
        max_size=20,
    ).map(lambda runs: [step for run in runs for step in run])
)
def test_reassembler_short_way_is_the_long_way(steps: list[tuple[bytes, float]]) -> None:
    parts, now = [], 0.0
    for data, gap in steps:
        now += gap
        parts.append((data, now))
    fast, slow = FeedbackReassembler("can0"), FeedbackReassembler("can0", fast=False)
    assert results(fast, parts) == results(slow, parts)
    assert (fast.bytes_fed, fast.bytes_framed, fast.bytes_discarded) == (
        slow.bytes_fed,
        slow.bytes_framed,
        slow.bytes_discarded,
    )


def reference_tally(items: list[Any], events: list[Event]) -> dict[str, Any]:
    """The counters as the figures define them, one item and one event at a time."""
    frames = chunks = size = bits = 0
    for item in items:
        size += len(item.data)
        if isinstance(item, CanFrame):
            frames += 1
            bits += (CAN_BITS_EXTENDED if item.extended else CAN_BITS_STANDARD) + 8 * len(item.data)
        else:
            chunks += 1
    counted = [e for e in events if e.topic != TOPIC_ANALYSIS_RESPONSE]
    commands: Counter[str] = Counter()
    kinds: Counter[str] = Counter()
    crc_checked = crc_errors = 0
    for event in counted:
        f = event.fields
        streamed = f.get("transport") == "stream" and f.get("crc_set", True)
        if event.topic == TOPIC_COMMAND:
            commands[str(f.get("name", "unknown"))] += 1
            crc_checked += bool(streamed)
        elif event.topic == TOPIC_DIAGNOSTICS:
            kinds[str(f.get("kind", "unknown"))] += 1
            crc_errors += f.get("kind") == CRC_MISMATCH
        elif event.topic in (TOPIC_GIMBAL_ATTITUDE, TOPIC_GIMBAL_RANGING):
            crc_checked += 1
        else:
            crc_checked += bool(streamed)
    return {
        "items": {"frames": frames, "chunks": chunks, "bytes": size},
        "bits": bits,
        "events": len(counted),
        "topics": Counter(e.topic for e in counted),
        "commands": commands,
        "kinds": kinds,
        "with_warnings": sum(1 for e in counted if e.warnings),
        "crc": (crc_checked, crc_errors),
    }


event_list = st.lists(
    st.builds(
        Event,
        st.sampled_from(
            [
                TOPIC_COMMAND,
                TOPIC_DIAGNOSTICS,
                TOPIC_GIMBAL_ATTITUDE,
                TOPIC_GIMBAL_RANGING,
                TOPIC_UAV_GPS,
                TOPIC_ANALYSIS_RESPONSE,
            ]
        ),
        st.floats(0, 100),
        st.sampled_from(["can0", "idu"]),
        st.fixed_dictionaries(
            {},
            optional={
                "name": st.sampled_from(["zoom", "gimbal_control"]),
                "kind": st.sampled_from([CRC_MISMATCH, "incomplete"]),
                "transport": st.sampled_from(["stream", "can"]),
                "crc_set": st.booleans(),
                "direction": st.sampled_from(["gs_to_idu", ""]),
            },
        ),
        st.lists(st.just("w"), max_size=1),
    ),
    max_size=40,
)


@settings(max_examples=300, deadline=None)
@given(st.lists(frames() | st.builds(StreamChunk, st.floats(0, 100), st.binary())), event_list)
def test_tally_folds_a_batch_as_the_figures_define(items: list[Any], events: list[Event]) -> None:
    tally = Tally()
    tally.add_items(items)
    tally.add_events(events)
    want = reference_tally(items, events)
    assert tally.items() == want["items"] and tally.bits == want["bits"]
    assert tally.events == want["events"] and tally.topics == want["topics"]
    assert tally.commands == want["commands"] and tally.kinds == want["kinds"]
    assert tally.diagnostics == sum(want["kinds"].values())
    assert tally.with_warnings == want["with_warnings"]
    assert (tally.crc_checked, tally.crc_errors) == want["crc"]
    feedback = [e for e in events if e.topic in (TOPIC_GIMBAL_ATTITUDE, TOPIC_GIMBAL_RANGING)]
    assert sum(t.count for t in tally.feedback.values()) == len(feedback)


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.sampled_from([0.0, 0.000_000_5, 0.5, 0.499_999_5, 0.75, 1.0, 1.25, 1.5, 3.0, 7.7]),
        min_size=0,
        max_size=300,
    ),
    st.floats(0, 2e9),
    st.integers(0, 4),
)
def test_many_feedback_messages_are_timed_as_one_by_one(
    steps: list[float], start: float, damaged_first: int
) -> None:
    """The counters time a feedback group's messages at once (``FeedbackTrack.add`` of many
    arrivals): the same longest gap (the first of the longest), the same silences and lost
    messages as one by one; the clock yields the same silences either way."""
    times = [start + sum(steps[: i + 1]) for i in range(len(steps))]
    one, many = FeedbackTrack(), FeedbackTrack()
    one_clock, many_clock = FeedbackClock(), FeedbackClock()
    for track, clock in ((one, one_clock), (many, many_clock)):
        if damaged_first:
            track.add(clock.messages("s", [start - 10]))  # type: ignore[arg-type]
            silence = clock.damaged("s", start - 10 + damaged_first)
            assert silence is not None
            track.damaged(silence)
    one_by_one = []
    for t in times:
        arrivals = one_clock.messages("s", [t])
        assert arrivals is not None
        one_by_one += list(arrivals)
        one.add(arrivals)
    arrivals = many_clock.messages("s", times)
    assert arrivals is not None
    many.add(arrivals)
    assert dataclasses.asdict(many) == dataclasses.asdict(one)
    assert list(arrivals) == one_by_one
    assert one_clock.last_arrival == many_clock.last_arrival
