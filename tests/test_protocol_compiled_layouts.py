"""Layouts, commands and feedback messages decode through one precompiled struct and a
made-for-the-layout function: the result is exactly what decoding field by field gives,
warnings included."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.protocol.codec import decode_command, decode_command_fields
from analyzer.protocol.command_decoders import COMMAND_DECODERS, decoder_for
from analyzer.protocol.command_table import COMMANDS
from analyzer.protocol.feedback import (
    ATTITUDE,
    FEEDBACK_ID_BYTES,
    RANGING,
    FeedbackLayout,
    decode_feedback_fields,
    message_decoder,
)
from analyzer.protocol.layout import Layout
from analyzer.protocol.uav import STATUS_FRAMES, USED_BYTES, eight_byte_decoder

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
    fields, warnings = eight_byte_decoder(can_id)(data)
    slow, slow_warnings = field_by_field(STATUS_FRAMES[can_id].layout, data)
    used = USED_BYTES[can_id]
    if any(data[used:]):
        slow_warnings.append(f"unused bytes {used}-7 are not zero: {data[used:].hex(' ').upper()}")
    assert (fields, warnings) == (slow, slow_warnings)
    assert list(fields) == list(slow)


# -- commands and feedback messages ------------------------------------------------------------

ROW_PREFIXES = sorted({(row.s_id, row.cmd) for row in COMMANDS})


@st.composite
def command_data(draw: st.DrawFn) -> bytes:
    """8 data bytes of a command of the table: random values, often zero, any selector."""
    s_id, cmd = draw(st.sampled_from(ROW_PREFIXES))
    rest = draw(st.lists(st.integers(0, 255) | st.just(0), min_size=6, max_size=6))
    return bytes([s_id, cmd, *rest])


def assert_same(
    fast: tuple[dict[str, Any], list[str]], slow: tuple[dict[str, Any], list[str]]
) -> None:
    assert fast == slow
    assert list(fast[0]) == list(slow[0])  # the same key order, so the same JSON
    assert [type(v) for v in fast[0].values()] == [type(v) for v in slow[0].values()]


def test_every_command_of_the_table_has_a_generated_decoder() -> None:
    for s_id, cmd in ROW_PREFIXES:
        assert decoder_for(s_id << 8 | cmd) is COMMAND_DECODERS[s_id << 8 | cmd]
    assert decoder_for(0x0F77) is None  # not in the table: decoded the long way


@pytest.mark.slow
@settings(max_examples=1000)
@given(command_data())
def test_generated_command_decoders_equal_field_by_field(data: bytes) -> None:
    decode = decoder_for(data[0] << 8 | data[1])
    assert decode is not None
    fast = decode(data)
    assert_same(fast, decode_command_fields(data))
    assert_same(decode_command(data), decode_command_fields(data))


@settings(max_examples=300)
@given(
    st.sampled_from([ATTITUDE, RANGING]),
    st.binary(min_size=32, max_size=32),
    st.sampled_from([b"", bytes(9), bytes(12)]),
)
def test_generated_feedback_decoders_equal_field_by_field(
    layout: FeedbackLayout, data: bytes, zeros: bytes
) -> None:
    # Often with the reserved bytes zero and the right id bytes, so that values are checked.
    message = bytearray(data)
    message[2] = layout.length_byte
    message[3 : 3 + len(zeros)] = zeros
    if zeros:
        message[12:16] = FEEDBACK_ID_BYTES
    fast = message_decoder(layout.length_byte)(bytes(message))
    found, *slow = decode_feedback_fields(bytes(message))
    assert found is layout
    assert_same(fast, (slow[0], slow[1]))
