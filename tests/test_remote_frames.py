"""Remote frames carry no data but request a length: every reader reports that DLC."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import can
import dpkt
import pytest

from analyzer.inputs import open_input
from analyzer.inputs.candump.reader import CandumpParser
from analyzer.mcapio.channels import can_frame_from_dict, can_frame_json
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.ids import PROTOCOL_IDS
from analyzer.protocol.types import CanFrame

T0 = 1715680800.0


def _frames(*lines: bytes, **kwargs: Any) -> list[CanFrame]:
    items = CandumpParser("test.log", **kwargs).parse_lines(list(lines))
    return [item for item in items if isinstance(item, CanFrame)]


@pytest.mark.parametrize(("text", "dlc"), [(b"123#R", 0), (b"123#R5", 5), (b"123#R8_9", 8)])
def test_candump_log_form_keeps_the_requested_dlc(text: bytes, dlc: int) -> None:
    (frame,) = _frames(b"(2.5) can0 " + text)
    assert frame.is_remote and frame.data == b"" and frame.dlc == dlc


def test_candump_screen_form_keeps_the_requested_dlc() -> None:
    (frame,) = _frames(b" (1436509052.249713)  can0  123   [5]  remote request")
    assert frame.is_remote and frame.data == b"" and frame.dlc == 5


def test_a_remote_frame_on_a_protocol_id_keeps_its_dlc_too() -> None:
    (frame,) = _frames(b"(2.5) can0 0000FF15#R6", wanted_ids=PROTOCOL_IDS)  # the fast path
    assert frame.is_remote and frame.dlc == 6


@pytest.mark.parametrize(
    "name", ["x.asc", "x.blf", "x.csv"]
)  # python-can writes no TRC remote frames
def test_python_can_logs_keep_the_requested_dlc(tmp_path: Path, name: str) -> None:
    path = tmp_path / name
    with can.Logger(str(path)) as logger:
        logger.on_message_received(
            can.Message(
                timestamp=T0,
                arbitration_id=0x123,
                is_extended_id=False,
                is_remote_frame=True,
                dlc=4,
                channel=0,
            )
        )
        logger.on_message_received(
            can.Message(
                timestamp=T0 + 0.1,
                arbitration_id=0x124,
                is_extended_id=False,
                data=b"\x01\x02",
                channel=0,
            )
        )
    frames = [f for f in open_input(str(path)) if isinstance(f, CanFrame)]
    assert [(f.is_remote, f.dlc, f.data) for f in frames] == [
        (True, 4, b""),
        (False, 2, b"\x01\x02"),
    ]


def test_socketcan_pcap_remote_frame_keeps_its_dlc(tmp_path: Path) -> None:
    path = tmp_path / "can.pcap"
    with path.open("wb") as f:
        writer = dpkt.pcap.Writer(f, linktype=227)
        header = (0x40000000 | 0x123).to_bytes(4, "big") + bytes([3, 0, 0, 0])  # RTR, len 3
        writer.writepkt(header, ts=T0)
    (frame,) = [f for f in open_input(str(path)) if isinstance(f, CanFrame)]
    assert frame.is_remote and frame.data == b"" and frame.dlc == 3


def test_other_frame_events_and_recordings_carry_the_requested_dlc() -> None:
    frame = CanFrame(T0, 0x123, b"", False, "can0", is_remote=True, remote_dlc=7)
    (event,) = ProtocolDecoder(emit_other=True).feed(frame)
    assert event.fields["dlc"] == 7 and event.fields["remote"] is True
    stored = json.loads(can_frame_json(frame))
    assert stored["dlc"] == 7
    assert can_frame_from_dict(stored) == frame
    data_frame = CanFrame(T0, 0x123, b"\x01\x02\x03", False, "can0")
    assert json.loads(can_frame_json(data_frame))["dlc"] == 3
    assert can_frame_from_dict(json.loads(can_frame_json(data_frame))) == data_frame


def test_decode_shows_the_requested_dlc(tmp_path: Path) -> None:
    from analyzer.render import render_event

    frame = CanFrame(T0, 0x123, b"", False, "can0", is_remote=True, remote_dlc=5)
    (event,) = ProtocolDecoder(emit_other=True).feed(frame)
    assert "0x123 [5] remote request" in render_event(event)
