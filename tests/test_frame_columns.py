"""Frames read as columns (``FrameColumns``) give what the same frames as CanFrames give.

The candump reader, the decoder and the counters each take a short way with columns;
each is held here to the long way: the same text read line by line as CanFrames, the
same frames fed one CanFrame at a time, the same frames counted as items, a pipeline
whose sink keeps raw frames and one whose sink does not.
"""

from __future__ import annotations

import dataclasses
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.inputs.base import by_frames
from analyzer.inputs.candump.reader import CandumpReader
from analyzer.pipeline import Batch, Pipeline, run_items
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, encode_ranging, segments
from analyzer.protocol.frame_columns import DIRECTIONS, FrameColumns
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    PROTOCOL_IDS,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.types import CanFrame, Event
from analyzer.protocol.uav import encode_altitude, encode_gps, encode_text, encode_uav_attitude
from analyzer.tally import Tally
from tests.candump_texts import CUTS, TEXTS, WANTED_SETS, parse, summary
from tests.fault_logs import CANDUMP_NAME, write_fault_logs

SAMPLES = Path(__file__).resolve().parents[1] / "samples"


def expanded(items: list[Any]) -> list[Any]:
    """Items with every FrameColumns replaced by its CanFrames."""
    out: list[Any] = []
    for item in items:
        out += item.frames() if isinstance(item, FrameColumns) else [item]
    return out


def parsed(text: bytes, cuts: list[int], wanted: frozenset[int] | None, columns: bool) -> Any:
    items, parser = parse(text, cuts, dense=columns, wanted_ids=wanted, columnar=columns)
    if columns:
        assert all(len(i) for i in items if isinstance(i, FrameColumns))
    return summary(expanded(items), parser)


@pytest.mark.slow
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(TEXTS, CUTS, WANTED_SETS)
def test_the_reader_gives_the_same_frames_as_columns(
    text: bytes, cuts: list[int], wanted: frozenset[int] | None
) -> None:
    assert parsed(text, cuts, wanted, columns=True) == parsed(text, cuts, wanted, columns=False)


# Data as the bus carries it: valid messages of each protocol ID, and anything else.
_FEEDBACK = [
    *segments(encode_attitude(pitch_deg=-30.0, yaw_deg=12.5, motor_yaw_deg=3.0)),
    *segments(
        encode_ranging(distance_m=120.0, height_m=80.0, latitude_deg=31.1, longitude_deg=118.1)
    ),
]
_DATA_BY_ID: dict[int, list[bytes]] = {
    CONTROL_ID: [
        encode_command("gimbal_control", pan_speed_dps=12.5, tilt_speed_dps=-3.0),
        encode_command("zoom", action="zoom_in"),
        encode_command("snapshot", mode="single"),
    ],
    FEEDBACK_ID: [bytes(s) for s in _FEEDBACK],
    GPS_ID: [encode_gps(31.12, 118.12)],
    ALTITUDE_ID: [encode_altitude(123.4)],
    UAV_ATTITUDE_ID: [encode_uav_attitude(1.5, -2.0, 90.0)],
    TEXT_ID: [d for i, d in encode_text("BATTERY LOW") if i == TEXT_ID],
    TEXT_END_ID: [d for i, d in encode_text("BATTERY LOW") if i == TEXT_END_ID],
}


@st.composite
def plain_frames(draw: st.DrawFn) -> list[CanFrame]:
    """Plain data frames of the protocol's IDs and others, in (mostly) time order."""
    out = []
    time = draw(st.floats(0, 2e9, allow_nan=False))
    for _ in range(draw(st.integers(0, 40))):
        time += draw(st.sampled_from([0.0, 0.001, 0.05, 0.3, 2.0, -0.5]))
        can_id = draw(st.sampled_from([*_DATA_BY_ID, 0x18F00000, 0x123, 0xF01]))
        known = _DATA_BY_ID.get(can_id, [])
        data = draw(
            st.sampled_from(known) if known and draw(st.booleans()) else st.binary(max_size=8)
        )
        out.append(
            CanFrame(
                time,
                can_id,
                data,
                draw(st.booleans()) if can_id <= 0x7FF else True,
                draw(st.sampled_from(["can0", "can1", ""])),
                direction=draw(st.sampled_from(["", "rx", "tx"])),
            )
        )
    return out


def as_columns(frames: list[CanFrame]) -> FrameColumns:
    channels = list(dict.fromkeys(f.channel for f in frames))
    data = np.zeros((len(frames), 8), np.uint8)
    for row, f in enumerate(frames):
        data[row, : len(f.data)] = np.frombuffer(f.data, np.uint8)
    return FrameColumns(
        np.array([f.time for f in frames], np.float64),
        np.array([f.can_id for f in frames], np.int64),
        np.array([f.extended for f in frames], bool),
        np.array([len(f.data) for f in frames], np.uint8),
        data,
        np.array([channels.index(f.channel) for f in frames], np.int32),
        channels,
        np.array([DIRECTIONS.index(f.direction) for f in frames], np.int8),
    )


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(st.lists(plain_frames(), max_size=4), st.booleans(), st.integers(1, 4))
def test_the_decoder_decodes_columns_as_the_same_frames_one_by_one(
    batches: list[list[CanFrame]], emit_other: bool, sources: int
) -> None:
    short = ProtocolDecoder(emit_other=emit_other, max_sources=sources)
    long = ProtocolDecoder(emit_other=emit_other, max_sources=sources)
    short_events: list[Event] = []
    long_events: list[Event] = []
    for frames in batches:
        columns = as_columns(frames)
        assert columns.frames() == frames
        short.feed_batch([columns], short_events)
        long.feed_batch(frames, long_events)
        assert short.last_time == long.last_time
    short_events += short.close()
    long_events += long.close()
    assert [e.to_dict() for e in short_events] == [e.to_dict() for e in long_events]
    assert short.stats == long.stats


@pytest.mark.slow
@given(st.lists(plain_frames(), max_size=4))
def test_the_counters_count_columns_as_the_same_frames(batches: list[list[CanFrame]]) -> None:
    short, long = Tally(), Tally()
    for frames in batches:
        if frames:
            short.add_runs([as_columns(frames)])
        long.add_items(frames)
    assert dataclasses.asdict(short) == dataclasses.asdict(long)


class Keeper:
    """A sink that keeps raw items (and every event), as an MCAP writer does."""

    keeps_items = True

    def __init__(self) -> None:
        self.items: list[Any] = []
        self.events: list[dict[str, Any]] = []

    def handle(self, batch: Batch) -> None:
        self.items += batch.items
        self.events += [e.to_dict() for e in batch.events]

    def close(self) -> None:
        pass


class EventsOnly(Keeper):
    keeps_items = False


def run_file(path: Path, sink: Keeper) -> tuple[Any, ...]:
    reader = CandumpReader(str(path), wanted_ids=PROTOCOL_IDS)
    pipeline = Pipeline([sink])
    run_items(reader, pipeline, batch_items=64)
    reader.close()
    stats = pipeline.decoder.stats  # type: ignore[attr-defined]
    return (
        sink.events,
        dataclasses.asdict(pipeline.tally),
        stats,
        reader.stats,
        (reader.first_time, reader.last_time),
    )


@pytest.mark.parametrize("name", ["flight-candump.log", CANDUMP_NAME])
def test_a_pipeline_without_raw_items_counts_columns_the_same(name: str, tmp_path: Path) -> None:
    write_fault_logs(tmp_path)
    path = SAMPLES / name if (SAMPLES / name).exists() else tmp_path / name
    keeper = Keeper()
    with_items = run_file(path, keeper)
    without = run_file(path, EventsOnly())
    assert with_items == without
    assert keeper.items and all(type(i) is CanFrame for i in keeper.items)


@given(st.lists(st.integers(0, 300), max_size=30), st.integers(1, 200))
def test_columns_go_to_the_pipeline_in_lists_of_at_most_a_batch_of_frames(
    lengths: list[int], size: int
) -> None:
    # Items as a block gives them: columns of frames and, between them, single items.
    items: list[Any] = [
        as_columns([CanFrame(float(i), CONTROL_ID, b"")] * n) if n else Event("/d", 0.0, "t")
        for i, n in enumerate(lengths)
    ]
    chunks = list(by_frames(items, size))
    assert [i for chunk in chunks for i in chunk] == items
    for chunk in chunks:
        weight = sum(len(i) if isinstance(i, FrameColumns) else 1 for i in chunk)
        assert weight <= size or len(chunk) == 1
    assert all(chunks) or chunks == [[]]


@st.composite
def feedback_stream(draw: st.DrawFn) -> list[CanFrame]:
    """Feedback as a gimbal sends it, with what goes wrong on a bus: whole messages one
    after the other, a last segment sent twice, a segment lost or late, a damaged byte."""
    out: list[CanFrame] = []
    time = 1e9
    for _ in range(draw(st.integers(0, 12))):
        message = draw(st.sampled_from(MESSAGES))
        parts = [bytes(p) for p in segments(message)]
        fault = draw(st.sampled_from(["none"] * 6 + ["repeat", "lose", "late", "flip"]))
        if fault == "repeat":
            parts.append(parts[-1])
        elif fault == "lose":
            del parts[draw(st.integers(0, 3))]
        elif fault == "flip":
            at = draw(st.integers(0, len(parts) - 1))
            parts[at] = bytes([parts[at][0] ^ 0x40]) + parts[at][1:]
        for part in parts:
            time += 0.3 if fault == "late" and draw(st.booleans()) else 0.001
            out.append(CanFrame(time, FEEDBACK_ID, part, True, draw(st.sampled_from(CHANNELS))))
        time += draw(st.sampled_from([0.001, 0.1, 0.5]))
    return out


MESSAGES = [
    encode_attitude(pitch_deg=-30.0, yaw_deg=12.5, motor_yaw_deg=3.0),
    encode_attitude(pitch_deg=-31.0, yaw_deg=12.5, motor_yaw_deg=3.0),
    encode_ranging(distance_m=120.0, height_m=80.0, latitude_deg=31.1, longitude_deg=118.1),
]
CHANNELS = ["can0", "can0", "can0", "can1"]


@settings(max_examples=300, deadline=None)
@given(feedback_stream(), st.lists(st.integers(0, 60), max_size=3))
def test_feedback_in_columns_is_reassembled_as_segment_by_segment(
    frames: list[CanFrame], cuts: list[int]
) -> None:
    """Messages taken whole in vectors, and everything around them, as the reassembler
    takes one segment at a time, wherever the blocks end."""
    short, long = ProtocolDecoder(), ProtocolDecoder()
    short_events: list[Event] = []
    long_events: list[Event] = []
    edges = sorted({0, len(frames), *(c for c in cuts if c < len(frames))})
    for start, end in pairwise(edges):
        short.feed_batch([as_columns(frames[start:end])], short_events)
        long.feed_batch(frames[start:end], long_events)
    short_events += short.close()
    long_events += long.close()
    assert [e.to_dict() for e in short_events] == [e.to_dict() for e in long_events]
    assert short.stats == long.stats
    short_tally, long_tally = Tally(), Tally()
    short_tally.add_events(short_events)
    long_tally.add_events(long_events)
    assert dataclasses.asdict(short_tally) == dataclasses.asdict(long_tally)
