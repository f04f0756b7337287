"""Error frames from every place they come: candump logs, SocketCAN pcaps, python-can's live
socketcan interface, and python-can's ASC and BLF files, as ``decode`` shows them.
"""

from __future__ import annotations

import json
import socket
import struct
import time
from pathlib import Path
from typing import Any

import can
import dpkt
import duckdb
import pytest
from can.interfaces.socketcan import constants, socketcan

from analyzer.cli import main
from analyzer.inputs.python_can.reader import frame_from_message
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.types import TOPIC_CAN_BUS_STATE, TOPIC_DIAGNOSTICS
from tests.platforms import linux

CAN_ERR_FLAG = 0x20000000
T0 = 1700000000.0
# The frames of a field laptop's bus: rx-error-passive, no ACK, bus-off, lost arbitration
# with the error counters at 128 / 136 (candump -L lines).
ISSUE_FRAMES = [
    (0x004, "0010000000000000"),
    (0x020, "0000000000000000"),
    (0x040, "0000000000000000"),
    (0x202, "0500000000008088"),
]
ISSUE_TEXTS = [
    "controller-problem{rx-error-passive}",
    "no-acknowledgement-on-tx",
    "bus-off",
    "lost-arbitration{at bit 5},error-counter-tx-rx{{128}{136}}",
]


def candump_log(path: Path, frames: list[tuple[int, str]] = ISSUE_FRAMES) -> Path:
    lines = [
        f"({T0 + i * 0.1:.6f}) can0 {CAN_ERR_FLAG | can_id:08X}#{data}\n"
        for i, (can_id, data) in enumerate(frames)
    ]
    path.write_text("".join(lines), encoding="utf-8")
    return path


def decoded(path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[list[dict[str, Any]], str]:
    assert main(["decode", str(path), "--json"]) == 0
    captured = capsys.readouterr()
    return [json.loads(line) for line in captured.out.splitlines()], captured.err


def bus_errors(events: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [e for e in events if e["topic"] == TOPIC_DIAGNOSTICS and e["kind"] == "bus_error"]


def test_candump_log_error_frames(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    events, err = decoded(candump_log(tmp_path / "bus.log"), capsys)
    errors = bus_errors(events)
    assert [e["error"] for e in errors] == ISSUE_TEXTS
    assert [e["bus_state"] for e in errors] == [
        "error-passive",
        "error-passive",
        "bus-off",
        "bus-off",
    ]
    assert errors[0]["classes"] == ["controller-problem"]
    assert errors[0]["controller"] == ["rx-error-passive"]
    assert (errors[3]["tx_errors"], errors[3]["rx_errors"]) == (128, 136)
    assert errors[3]["raw"] == "05 00 00 00 00 00 80 88"
    states = [e for e in events if e["topic"] == TOPIC_CAN_BUS_STATE]
    assert [s["state"] for s in states] == ["error-passive", "bus-off", "bus-off"]
    assert states[-1]["tx_errors"] == 128
    # Error frames are no reason to doubt the bus; the hints say what to do instead.
    assert "is this the gimbal's bus" not in err
    assert "nothing on the bus acknowledges" in err
    assert "went bus-off at 2023-11-14 22:13:20.200Z and stayed there" in err


def test_a_protocol_violation_in_text_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = candump_log(tmp_path / "stuff.log", [(0x088, "0000041900000000")])
    assert main(["decode", str(path)]) == 0
    out = capsys.readouterr().out
    assert (
        "BUS_ERROR        CAN error frame: protocol-violation{{bit-stuffing-error}"
        "{acknowledge-slot}},bus-error; bus error-active  raw 00 00 04 19 00 00 00 00"
    ) in out


def test_summary_names_worst_state_counts_and_hints(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = candump_log(tmp_path / "bus.log")
    assert main(["decode", str(path), "--summary"]) == 0
    out = capsys.readouterr().out
    assert "4 CAN frames (0 protocol, 0 other, 4 error frames)" in out
    assert "worst bus-off at 2023-11-14 22:13:20.200Z, now bus-off" in out
    assert "error counters up to tx 128 rx 136" in out
    assert "no-acknowledgement-on-tx 1" in out
    assert "hint" in out and "1 Mbit/s" in out
    assert main(["decode", str(path), "--summary", "--json"]) == 0
    bus = json.loads(capsys.readouterr().out)["bus"]
    assert (bus["worst_state"], bus["worst_time"]) == ("bus-off", T0 + 0.2)
    assert bus["classes"]["bus-off"] == 1


def test_only_error_frames_means_another_bitrate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An adapter at 500 kbit/s on the gimbal's 1 Mbit/s bus sees nothing but errors."""
    stuff = [(0x088, "0000040a00000000")] * 20
    _, err = decoded(candump_log(tmp_path / "bitrate.log", stuff), capsys)
    assert "received only error frames (20), no data frame: its bitrate is not the bus's" in err
    assert "is this the gimbal's bus" not in err


def test_many_stuff_errors_among_data_frames_mean_bitrate_or_termination(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "noisy.log"
    lines = [f"({T0 + i * 0.01:.6f}) can0 00000F01#0F04000000000000\n" for i in range(5)]
    lines += [f"({T0 + 1 + i * 0.01:.6f}) can0 20000088#0000020a00000000\n" for i in range(12)]
    path.write_text("".join(lines), encoding="utf-8")
    _, err = decoded(path, capsys)
    assert "12 stuff / form / bit errors: the bitrate or the termination is wrong" in err


def test_malformed_error_frame_is_a_diagnostic_with_its_bytes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "bad.log"
    path.write_text(f"({T0:.6f}) can0 20000C04#0010\n", encoding="utf-8")
    events, _ = decoded(path, capsys)
    (error,) = bus_errors(events)
    assert error["raw"] == "00 10"
    assert "unknown error class bits 0x00000C00" in error["malformed"]
    assert "2 data bytes; an error frame has 8" in error["malformed"]
    assert error["detail"].startswith("malformed CAN error frame")


def test_socketcan_pcap(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Wireshark / tcpdump on can0 (LINKTYPE_CAN_SOCKETCAN, IDs in network byte order):
    the kernel's error frames carry CAN_ERR_FLAG and no CAN_EFF_FLAG."""
    path = tmp_path / "can0.pcap"
    with path.open("wb") as handle:
        writer = dpkt.pcap.Writer(handle, linktype=227)
        for i, (can_id, data) in enumerate(ISSUE_FRAMES):
            packet = struct.pack(">IB3x", CAN_ERR_FLAG | can_id, 8) + bytes.fromhex(data)
            writer.writepkt(packet, ts=T0 + i * 0.1)
    events, _ = decoded(path, capsys)
    assert [e["error"] for e in bus_errors(events)] == ISSUE_TEXTS


@linux
def test_live_socketcan_through_python_can(tmp_path: Path) -> None:
    """python-can's socketcan receive code (``capture_message``) on the bytes a CAN_RAW
    socket delivers (struct can_frame plus its SO_TIMESTAMPNS), then the decoder."""
    sender, receiver = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
    receiver.setsockopt(socket.SOL_SOCKET, constants.SO_TIMESTAMPNS, 1)
    decoder = ProtocolDecoder()
    texts = []
    try:
        for can_id, data in ISSUE_FRAMES:
            sender.send(struct.pack("=IB3x8s", CAN_ERR_FLAG | can_id, 8, bytes.fromhex(data)))
            message = socketcan.capture_message(receiver, get_channel=False)
            assert message is not None and message.is_error_frame
            frame = frame_from_message(message, "can0")
            texts.extend(
                e.fields["error"] for e in decoder.feed(frame) if e.topic == TOPIC_DIAGNOSTICS
            )
    finally:
        sender.close()
        receiver.close()
    assert texts == ISSUE_TEXTS


def messages() -> list[can.Message]:
    return [
        can.Message(
            timestamp=T0 + i * 0.1,
            arbitration_id=can_id,
            is_extended_id=False,
            is_error_frame=True,
            data=bytes.fromhex(data),
            channel=0,
        )
        for i, (can_id, data) in enumerate(ISSUE_FRAMES)
    ]


def test_blf_written_by_python_can(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "bus.blf"
    with can.BLFWriter(str(path)) as writer:
        for message in messages():
            writer.on_message_received(message)
    events, _ = decoded(path, capsys)
    assert [e["error"] for e in bus_errors(events)] == ISSUE_TEXTS


def test_asc_error_frames_written_by_python_can(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """ASC keeps only that an error frame was seen (``ErrorFrame``): unspecified errors."""
    path = tmp_path / "bus.asc"
    with can.ASCWriter(str(path)) as writer:
        for message in messages():
            writer.on_message_received(message)
    assert path.read_text(encoding="utf-8").count("ErrorFrame") == 4
    events, err = decoded(path, capsys)
    errors = bus_errors(events)
    assert [e["error"] for e in errors] == ["unspecified"] * 4
    assert "malformed" not in errors[0]
    assert "received only error frames (4)" in err


def test_report_names_the_worst_state_and_what_to_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "report.html"
    assert main(["report", str(candump_log(tmp_path / "bus.log")), "-o", str(out)]) == 0
    page = out.read_text(encoding="utf-8")
    assert "worst bus-off at 2023-11-14 22:13:20.200Z on can0" in page
    assert "nothing on the bus acknowledges the frames sent" in page
    assert "received only error frames (4)" in page


def test_fleet_table_has_the_worst_state_per_recording(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    flights = tmp_path / "flights"
    flights.mkdir()
    candump_log(flights / "bus.log")
    dataset = tmp_path / "dataset"
    assert main(["table", str(flights), "-o", str(dataset)]) == 0
    pattern = dataset / "recordings" / "*.parquet"
    ((state, when, errors),) = duckdb.sql(
        f"SELECT bus_worst_state, epoch_ms(bus_worst_time), diag_bus_error "
        f"FROM read_parquet('{pattern}')"
    ).fetchall()
    assert (state, when, errors) == ("bus-off", round((T0 + 0.2) * 1000), 4)
    pattern = dataset / "diagnostics" / "*.parquet"
    ((text, classes),) = duckdb.sql(
        f"SELECT error, classes FROM read_parquet('{pattern}') WHERE tx_errors = 128"
    ).fetchall()
    assert text == ISSUE_TEXTS[3] and classes == ["lost-arbitration", "error-counter-tx-rx"]


def test_live_capture_records_the_bus_state(tmp_path: Path) -> None:
    """Error frames from a live python-can bus, through the capture engine into a recording
    whose /can/bus_state messages match their schema and whose record names the bus-off."""
    import uuid

    import jsonschema
    from mcap.reader import make_reader

    from analyzer.capture import Capture
    from analyzer.mcapio.read.info import recording_info
    from analyzer.mcapio.write.sink import McapSink
    from analyzer.protocol.schema import topic_schemas
    from analyzer.sources import open_source

    channel = f"err-{uuid.uuid4().hex[:8]}"
    sender = can.Bus(interface="virtual", channel=channel)
    source = open_source(f"can:virtual:{channel}")
    path = tmp_path / "bus.mcap"
    capture = Capture(source, [McapSink(path, metadata={"source": source.description})])
    capture.start()
    try:
        for message in messages():
            sender.send(message)
        deadline = time.monotonic() + 5.0
        while capture.stats.frames < len(ISSUE_FRAMES):
            assert time.monotonic() < deadline, "timed out"
            time.sleep(0.01)
    finally:
        capture.stop()
        assert capture.join(5.0)
        sender.shutdown()
    assert capture.error is None
    validator = jsonschema.Draft202012Validator(topic_schemas()[TOPIC_CAN_BUS_STATE])
    with path.open("rb") as handle:
        states = [
            json.loads(message.data)
            for _, ch, message in make_reader(handle).iter_messages()
            if ch.topic == TOPIC_CAN_BUS_STATE
        ]
    for state in states:
        validator.validate(state)
    assert [s["state"] for s in states] == ["error-passive", "bus-off", "bus-off"]
    bus = recording_info(path).tally.bus.figures()
    assert bus["worst_state"] == "bus-off" and bus["error_frames"] == 4


def test_error_frames_of_an_adapter_with_its_own_encoding_are_unspecified() -> None:
    """PCAN puts its error type in the ID (4: stuff error) and its counters elsewhere: that
    is no SocketCAN class, so the frame counts as an unspecified error, bytes kept."""
    import uuid

    from analyzer.sources.can_bus import CanSource
    from analyzer.sources.spec import CanSpec

    channel = f"pcan-{uuid.uuid4().hex[:8]}"
    sender = can.Bus(interface="virtual", channel=channel)
    bus = can.Bus(interface="virtual", channel=channel)
    source = CanSource(CanSpec("pcan", "PCAN_USBBUS1", 1_000_000), open_bus=lambda spec: bus)
    try:
        sender.send(can.Message(arbitration_id=4, is_error_frame=True, data=b"\x00\x00\x07\x02"))
        deadline = time.monotonic() + 5.0
        frames: list[Any] = []
        while not frames:
            assert time.monotonic() < deadline, "timed out"
            frames = [i for i in source.read(0.05) if getattr(i, "is_error", False)]
    finally:
        source.close()
        sender.shutdown()
    assert (frames[0].can_id, frames[0].data) == (0, b"\x00\x00\x07\x02")
    (diagnostic, _state) = ProtocolDecoder().feed(frames[0])
    assert diagnostic.fields["error"] == "unspecified"
    assert diagnostic.fields["raw"] == "00 00 07 02" and "malformed" not in diagnostic.fields
