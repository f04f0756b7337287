"""Layouts decode through one precompiled struct and a made-for-the-layout function: the
result is exactly what decoding field by field gives, warnings included."""

from __future__ import annotations

from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.protocol.feedback import ATTITUDE, RANGING
from analyzer.protocol.fields import Layout
from analyzer.protocol.uav import EIGHT_BYTE_DECODERS, STATUS_FRAMES, USED_BYTES

LAYOUTS: list[Layout] = [
    ATTITUDE.layout,
    RANGING.layout,
    *(status.layout for status in STATUS_FRAMES.values()),
]


def field_by_field(layout: Layout, data: bytes) -> tuple[dict[str, Any], list[str]]:
    out: dict[str, Any] = {}
    warnings: list[str] = []
    for f in layout.fields:
        f.decode_into(data, out, warnings)
    return out, warnings


def test_every_layout_has_a_precompiled_struct() -> None:
    for layout in LAYOUTS:
        assert layout._struct is not None  # type: ignore[attr-defined]


@settings(max_examples=200)
@given(st.sampled_from(LAYOUTS), st.binary(min_size=32, max_size=32))
def test_compiled_decoding_equals_field_by_field(layout: Layout, data: bytes) -> None:
    warnings: list[str] = []
    fast = layout.decode(data, warnings)
    slow, slow_warnings = field_by_field(layout, data)
    assert fast == slow
    assert list(fast) == list(slow)  # the same key order, so the same JSON
    assert warnings == slow_warnings
    assert [type(v) for v in fast.values()] == [type(v) for v in slow.values()]


@settings(max_examples=200)
@given(st.sampled_from(sorted(STATUS_FRAMES)), st.binary(min_size=8, max_size=8))
def test_eight_byte_status_frames_decode_in_one_call_as_field_by_field(
    can_id: int, data: bytes
) -> None:
    fields, warnings = EIGHT_BYTE_DECODERS[can_id](data)
    slow, slow_warnings = field_by_field(STATUS_FRAMES[can_id].layout, data)
    used = USED_BYTES[can_id]
    if any(data[used:]):
        slow_warnings.append(f"unused bytes {used}-7 are not zero: {data[used:].hex(' ').upper()}")
    assert (fields, warnings) == (slow, slow_warnings)
    assert list(fields) == list(slow)
