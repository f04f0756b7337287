"""SocketCAN error frames: decoded as linux/can/error.h defines them, in candump -e words.

The texts are those of can-utils' ``snprintf_can_error_frame`` (lib.c), joined with its
default separator ``,``. The controller's state follows from the frames per channel:
error-active, error-warning, error-passive, bus-off, and back on a restart.
"""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from analyzer.protocol.bus_state import (
    BUS_OFF,
    BUS_STATES,
    ERROR_ACTIVE,
    ERROR_PASSIVE,
    ERROR_WARNING,
    next_state,
)
from analyzer.protocol.can_error import CLASS_NAMES, KNOWN_CLASSES, decode_error_frame
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.types import (
    BUS_ERROR,
    TOPIC_CAN_BUS_STATE,
    TOPIC_DIAGNOSTICS,
    CanFrame,
    Event,
)


def frame(can_id: int, data: str, t: float = 1.0, channel: str = "can0") -> CanFrame:
    return CanFrame(t, can_id, bytes.fromhex(data), True, channel, is_error=True)


# -- the frames of linux/can/error.h ------------------------------------------------------------


def test_controller_problem_rx_error_passive() -> None:
    error = decode_error_frame(0x004, bytes.fromhex("0010000000000000"))
    assert error.text == "controller-problem{rx-error-passive}"
    assert error.classes == ("controller-problem",)
    assert error.controller == ("rx-error-passive",)
    assert error.tx_errors is None and error.problems == ()


def test_no_acknowledgement_and_bus_off_and_restart() -> None:
    assert decode_error_frame(0x020, bytes(8)).text == "no-acknowledgement-on-tx"
    assert decode_error_frame(0x040, bytes(8)).text == "bus-off"
    assert decode_error_frame(0x100, bytes(8)).text == "restarted-after-bus-off"


def test_lost_arbitration_with_error_counters() -> None:
    error = decode_error_frame(0x202, bytes.fromhex("0500000000008088"))
    assert error.text == "lost-arbitration{at bit 5},error-counter-tx-rx{{128}{136}}"
    assert error.lost_arbitration_bit == 5
    assert (error.tx_errors, error.rx_errors) == (128, 136)


def test_protocol_violation_type_and_location() -> None:
    error = decode_error_frame(0x088, bytes.fromhex("0000041900000000"))
    assert error.text == "protocol-violation{{bit-stuffing-error}{acknowledge-slot}},bus-error"
    assert error.protocol == ("bit-stuffing-error",)
    assert error.location == "acknowledge-slot"
    unspecified = decode_error_frame(0x008, bytes.fromhex("0000020000000000"))
    assert unspecified.text == "protocol-violation{{frame-format-error}{}}"
    assert unspecified.location == "unspecified"


def test_counters_without_their_class_are_shown_as_candump_shows_them() -> None:
    # Drivers from before CAN_ERR_CNT put the counters into a controller-problem frame.
    error = decode_error_frame(0x004, bytes.fromhex("0004000000006000"))
    assert error.text == "controller-problem{rx-error-warning},error-counter-tx-rx{{96}{0}}"
    assert (error.tx_errors, error.rx_errors) == (96, 0)


def test_transceiver_status() -> None:
    error = decode_error_frame(0x010, bytes.fromhex("0000000040000000"))
    assert error.text == "transceiver-status{canl-no-wire}"
    assert error.transceiver == "canl-no-wire"


def test_an_error_frame_without_class_is_unspecified() -> None:
    """An ASC ``ErrorFrame`` line, or an adapter that encodes errors its own way."""
    for data in (b"", bytes.fromhex("0400000000000080")):
        error = decode_error_frame(0, data)
        assert (error.text, error.classes, error.problems) == ("unspecified", ("unspecified",), ())
        assert error.tx_errors is None


def test_unknown_class_bits_and_short_data_are_said() -> None:
    error = decode_error_frame(0x404, bytes.fromhex("00"))
    assert error.text == "controller-problem{},unknown-class{0x00000400}"
    assert error.problems == (
        "unknown error class bits 0x00000400",
        "1 data bytes; an error frame has 8 (no details for controller-problem)",
    )
    counters = decode_error_frame(0x200, bytes(3))
    assert counters.text == "error-counter-tx-rx{?}" and counters.tx_errors is None


@given(can_id=st.integers(0, 0x1FFFFFFF), data=st.binary(max_size=64))
def test_any_id_and_data_decode_without_an_exception(can_id: int, data: bytes) -> None:
    error = decode_error_frame(can_id, data)
    assert error.text and error.classes
    well_formed = not can_id & ~KNOWN_CLASSES and len(data) == 8
    if well_formed and data[3] < 32 and data[1] < 0x80:
        assert error.problems == ()
    if can_id & ~KNOWN_CLASSES or (len(data) != 8 and can_id):
        assert error.problems
    for i, name in enumerate(CLASS_NAMES):
        assert (name in error.classes) == bool(can_id >> i & 1)
    if can_id and len(data) >= 8 and (can_id & 0x200 or data[6] or data[7]):
        assert (error.tx_errors, error.rx_errors) == (data[6], data[7])
    else:
        assert error.tx_errors is None


@given(can_id=st.integers(0, 0x1FFFFFFF), data=st.binary(max_size=64), extended=st.booleans())
def test_the_decoder_turns_any_error_frame_into_a_diagnostic_with_its_bytes(
    can_id: int, data: bytes, extended: bool
) -> None:
    events = ProtocolDecoder().feed(CanFrame(5.0, can_id, data, extended, "can0", is_error=True))
    diagnostic = events[0]
    assert diagnostic.topic == TOPIC_DIAGNOSTICS
    assert diagnostic.fields["kind"] == BUS_ERROR
    assert diagnostic.fields["raw"] == data.hex(" ").upper()
    assert diagnostic.fields["bus_state"] in BUS_STATES
    assert ("malformed" in diagnostic.fields) == ("malformed" in diagnostic.fields["detail"])
    assert [e.topic for e in events[1:]] == [TOPIC_CAN_BUS_STATE]  # the first error frame


# -- the controller's state ---------------------------------------------------------------------


def states(decoder: ProtocolDecoder, frames: list[CanFrame]) -> list[str]:
    events: list[Event] = []
    for f in frames:
        events.extend(decoder.feed(f))
    return [str(e.fields["bus_state"]) for e in events if e.topic == TOPIC_DIAGNOSTICS]


def test_state_goes_down_to_bus_off_and_back_on_restart() -> None:
    frames = [
        frame(0x004, "0004000000000000", 1.0),  # rx-error-warning
        frame(0x004, "0010000000000000", 2.0),  # rx-error-passive
        frame(0x020, "0000000000000000", 2.5),  # no ACK: no state in it
        frame(0x040, "0000000000000000", 3.0),  # bus-off
        frame(0x200, "0000000000000010", 3.5),  # counters alone do not leave bus-off
        frame(0x100, "0000000000000000", 4.0),  # restarted
    ]
    assert states(ProtocolDecoder(), frames) == [
        ERROR_WARNING,
        ERROR_PASSIVE,
        ERROR_PASSIVE,
        BUS_OFF,
        BUS_OFF,
        ERROR_ACTIVE,
    ]


def test_state_from_the_error_counters_and_back_to_error_active() -> None:
    frames = [
        frame(0x200, "0000000000006000", 1.0),  # tx 96: warning
        frame(0x202, "0500000000008088", 2.0),  # rx 136: passive
        frame(0x004, "0040000000000000", 3.0),  # back-to-error-active
    ]
    assert states(ProtocolDecoder(), frames) == [ERROR_WARNING, ERROR_PASSIVE, ERROR_ACTIVE]


def test_each_channel_has_its_own_state() -> None:
    decoder = ProtocolDecoder()
    assert states(decoder, [frame(0x040, "00" * 8, 1.0, "can0")]) == [BUS_OFF]
    assert states(decoder, [frame(0x020, "00" * 8, 1.1, "can1")]) == [ERROR_ACTIVE]


def test_bus_state_messages_at_each_change_and_every_second() -> None:
    decoder = ProtocolDecoder()
    events: list[Event] = []
    for i in range(32):  # 3.1 s of no-ACK frames every 0.1 s, bus-off at 2.05 s
        events.extend(decoder.feed(frame(0x020, "00" * 8, 10.0 + i * 0.1)))
        if i == 20:
            events.extend(decoder.feed(frame(0x040, "00" * 8, 12.05)))
    published = [e for e in events if e.topic == TOPIC_CAN_BUS_STATE]
    assert [(round(e.time, 2), e.fields["state"]) for e in published] == [
        (10.0, ERROR_ACTIVE),
        (11.0, ERROR_ACTIVE),
        (12.0, ERROR_ACTIVE),
        (12.05, BUS_OFF),
        (13.1, BUS_OFF),
    ]
    last = published[-1].fields
    assert last["level"] == 3
    assert last["counts"] == {"bus_off": 1, "no_acknowledgement_on_tx": 32}
    assert last["since"] == 12.05


@given(st.lists(st.tuples(st.integers(0, 0x3FF), st.binary(min_size=8, max_size=8))))
def test_only_bus_off_classes_reach_bus_off(frames: list[tuple[int, bytes]]) -> None:
    state = ERROR_ACTIVE
    for can_id, data in frames:
        after = next_state(state, decode_error_frame(can_id, data))
        assert after in BUS_STATES
        if after == BUS_OFF and state != BUS_OFF:
            assert can_id & 0x040
        state = after


# -- the monitor's status line ------------------------------------------------------------------


def test_status_line_shows_state_worst_and_classes() -> None:
    from analyzer.pipeline import Batch
    from analyzer.tui.state import MonitorState
    from analyzer.tui.status_bar import StatusInfo, render_status

    decoder = ProtocolDecoder()
    state = MonitorState()
    frames = [
        frame(0x040, "00" * 8, 1700000000.0),
        frame(0x100, "00" * 8, 1700000002.0),
        frame(0x020, "00" * 8, 1700000003.0),
    ]
    events = [e for f in frames for e in decoder.feed(f)]
    state.fold(Batch(list(frames), events), wall_time=1700000003.0)
    text = render_status(state, StatusInfo(source="can:socketcan:can0")).plain
    assert "CAN error-active  worst bus-off 22:13:20.000Z" in text
    assert "3 error frames: bus-off 1, restarted-after-bus-off 1" in text


def test_foxglove_log_levels_follow_the_state() -> None:
    from analyzer.mcapio.foxglove import LOG_ERROR, LOG_INFO, LOG_WARNING, log_level

    decoder = ProtocolDecoder()
    levels = [
        log_level(e)
        for f in [
            frame(0x020, "00" * 8, 1.0),  # no ACK on a healthy controller
            frame(0x040, "00" * 8, 2.0),  # bus-off
            frame(0x100, "00" * 8, 3.0),  # restarted
        ]
        for e in decoder.feed(f)
        if e.topic == TOPIC_DIAGNOSTICS
    ]
    assert levels == [LOG_WARNING, LOG_ERROR, LOG_INFO]


def test_status_line_says_when_a_bus_went_off_while_it_still_is() -> None:
    from analyzer.pipeline import Batch
    from analyzer.tui.state import MonitorState
    from analyzer.tui.status_bar import StatusInfo, render_status

    state = MonitorState()
    bus_off = frame(0x040, "00" * 8, 1700000000.0)
    state.fold(Batch([bus_off], ProtocolDecoder().feed(bus_off)), wall_time=1700000000.5)
    text = render_status(state, StatusInfo(source="can:socketcan:can0")).plain
    assert "CAN bus-off  worst bus-off 22:13:20.000Z  1 error frame: bus-off 1" in text
