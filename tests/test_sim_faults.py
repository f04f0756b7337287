"""Fault injection on feedback segments and the diagnostics the analyzer reports for each."""

from __future__ import annotations

from collections import Counter

import pytest

from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.types import (
    CRC_MISMATCH,
    DUPLICATE,
    INCOMPLETE,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    CanFrame,
    Event,
)
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.faults import FaultConfig, FaultInjector

SECONDS = 60.0  # 120 feedback messages, 480 segments


def run(seconds: float = SECONDS, **faults: float) -> tuple[list[Event], SimulatedGimbal]:
    config = SimConfig(faults=FaultConfig(seed=3, **faults))
    gimbal = SimulatedGimbal(0.0, config)
    decoder = ProtocolDecoder()
    events: list[Event] = []
    t = 0.0
    while t <= seconds:
        for can_id, data in gimbal.poll(t):
            events.extend(decoder.feed(CanFrame(t, can_id, data)))
        t = round(t + 0.01, 6)
    return events + decoder.close(t), gimbal


def kinds(events: list[Event]) -> Counter[str]:
    return Counter(str(e.fields["kind"]) for e in events if e.topic == TOPIC_DIAGNOSTICS)


def attitudes(events: list[Event]) -> list[Event]:
    return [e for e in events if e.topic == TOPIC_GIMBAL_ATTITUDE]


def test_no_faults_no_diagnostics() -> None:
    events, gimbal = run()
    assert kinds(events) == Counter()
    assert len(attitudes(events)) == gimbal.sent["attitude"] == 121


def test_corrupted_segments_are_crc_mismatches() -> None:
    events, gimbal = run(corrupt=0.1)
    found = kinds(events)
    assert set(found) == {CRC_MISMATCH}
    # Each corrupted message is lost as one CRC mismatch; the others decode.
    assert found[CRC_MISMATCH] + len(attitudes(events)) == gimbal.sent["attitude"]
    assert gimbal.faults.counts["corrupt"] >= found[CRC_MISMATCH] > 20


def test_dropped_segments_are_incomplete_messages() -> None:
    events, gimbal = run(drop=0.1)
    found = kinds(events)
    assert found[INCOMPLETE] > 20
    # Two drops in a row can splice two messages into one whose CRC then fails.
    assert found[CRC_MISMATCH] <= found[INCOMPLETE] // 5
    assert set(found) <= {INCOMPLETE, CRC_MISMATCH}
    assert gimbal.faults.counts["drop"] > 30


def test_duplicated_segments_are_reported_as_duplicates() -> None:
    events, gimbal = run(duplicate=0.1)
    found = kinds(events)
    assert found[DUPLICATE] > 20
    # Every repeat is reported as one, the repeat of a last segment included.
    assert set(found) == {DUPLICATE}
    assert found[DUPLICATE] == gimbal.faults.counts["duplicate"]
    repeated = [w for e in attitudes(events) for w in e.warnings if "was repeated" in w]
    assert 0 < len(repeated) < found[DUPLICATE]
    # A repeated message survives its duplicate: nearly every message still decodes.
    assert len(attitudes(events)) >= gimbal.sent["attitude"] - 3


def test_delayed_segments_give_late_segment_warnings() -> None:
    events, gimbal = run(delay=0.1)
    assert kinds(events) == Counter()
    late = [e for e in attitudes(events) if any("late segment" in w for w in e.warnings)]
    assert len(late) > 10
    # Nothing is lost; the last message may still wait in the queue when the run ends.
    assert len(attitudes(events)) >= gimbal.sent["attitude"] - 1


def test_feedback_stops_for_the_configured_window() -> None:
    events, gimbal = run(10.0, stop_at=2.0, stop_for=3.0)
    times = [e.time for e in attitudes(events)]
    assert not [t for t in times if 2.0 <= t < 5.0]
    assert 1.5 in times and 5.0 in times
    assert gimbal.sent["attitude_suppressed"] == 6


def test_same_seed_same_faults() -> None:
    first, _ = run(10.0, drop=0.1, corrupt=0.1, duplicate=0.1, delay=0.1)
    second, _ = run(10.0, drop=0.1, corrupt=0.1, duplicate=0.1, delay=0.1)
    assert [e.to_dict() for e in first] == [e.to_dict() for e in second]


def test_corruption_never_touches_the_header_or_the_padding() -> None:
    injector = FaultInjector(FaultConfig(corrupt=1.0, seed=1))
    message = encode_attitude(pitch_deg=-10, yaw_deg=20)
    for _ in range(200):
        sent = b"".join(segment for _, segment in injector.segments(message))
        changed = [i for i in range(32) if sent[i] != message[i]]
        assert changed and all(3 <= i < 27 for i in changed)


def test_delay_keeps_the_segments_in_order() -> None:
    injector = FaultInjector(FaultConfig(delay=1.0, delay_s=0.25, seed=1))
    message = encode_attitude(pitch_deg=0, yaw_deg=0)
    out = injector.segments(message)
    assert [d for d, _ in out] == [0.25, 0.5, 0.75, 1.0]
    assert [s for _, s in out] == segments(message)


@pytest.mark.parametrize("rate", [-0.1, 1.5])
def test_rates_out_of_range_are_refused(rate: float) -> None:
    with pytest.raises(ValueError, match="between 0 and 1"):
        FaultConfig(drop=rate)


def test_describe_lists_the_faults() -> None:
    text = FaultConfig(drop=0.05, corrupt=0.02, stop_at=10, stop_for=3, seed=1).describe()
    assert text == "drop 5%, corrupt 2%, no feedback from 10 s for 3 s (seed 1)"
    assert FaultConfig().describe() == "none"
