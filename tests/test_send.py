"""`gimbal-analyzer send`: options from the table, the document's examples, errors, transmit."""

from __future__ import annotations

import argparse
import socket
import threading
import uuid

import pytest

from analyzer.cli import main
from analyzer.commands import send
from analyzer.errors import UsageError
from analyzer.protocol.command_table import BY_NAME, COMMANDS
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.types import TOPIC_COMMAND, CanFrame, StreamChunk
from analyzer.sim.transports import SimulatedCanLink, parse_link


def run_send(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(["send", *args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize(
    ("args", "data"),
    [
        (["forward"], "0F 02 00 00 00 00 00 00"),
        (["gimbal_control", "--pan-speed", "-5"], "0F 04 0C FE 00 00 00 00"),  # turn left 5 deg/s
        (["gimbal_control", "--tilt-speed-dps", "5"], "0F 04 00 00 F4 01 00 00"),  # pull up 5
        (["specified_angle", "--yaw", "45"], "0F 08 01 C2 01 00 00 00"),
        (["specified_angle", "--pitch", "-45"], "0F 08 02 3E FE 00 00 00"),
        (["specified_angle", "--zoom", "10"], "0F 08 03 E8 03 00 00 00"),
        (["snapshot", "--mode", "single"], "0F 10 01 00 00 00 00 00"),
        (["recording", "start"], "0F 11 01 00 00 00 00 00"),
        (["recording", "--action", "1"], "0F 11 01 00 00 00 00 00"),
        (["palette", "iron_red"], "1F 02 02 00 00 00 00 00"),
        (["gimbal_control", "--component", "dual_sensor", "--pan-speed", "1"], "1F 04 64 00"),
        (["tracking_stop", "--s-id", "0x1F"], "1F 07 00 00 00 00 00 00"),
        (
            ["specified_angle", "--yaw", "45", "--coordinate-system", "airframe"],
            "0F 08 01 C2 01 01",
        ),
    ],
)
def test_examples_of_the_document(
    capsys: pytest.CaptureFixture[str], args: list[str], data: str
) -> None:
    code, out, err = run_send(capsys, *args)
    assert (code, err) == (0, "")
    assert f"CAN data   {data}" in out
    assert "not sent" in out


def test_cansend_and_tcp_forms(capsys: pytest.CaptureFixture[str]) -> None:
    _, out, _ = run_send(capsys, "gimbal_control", "--pan-speed", "-5")
    assert "cansend    00000F01#0F040CFE00000000" in out
    assert "gimbal_control pan_speed_dps=-5 tilt_speed_dps=0" in out
    assert "--repeat 50ms" in out  # the hint that gimbal_control must be repeated
    _, out, _ = run_send(capsys, "look_down")  # the corrected frame of docs/protocol-notes.md
    assert (
        "TCP frame  EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5E" in out
    )
    _, out, _ = run_send(capsys, "gimbal_control", "--pan-speed", "80")
    assert out.splitlines()[3].endswith("0F 04 40 1F 00 00 00 00 C0 5C")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["gimbal_control", "--pan-speed", "150"],
            "pan_speed_dps: 150 out of range [-100.00, 100.00] deg/s",
        ),
        (["specified_angle", "--pitch", "-120"], "out of range [-100.0, 60.0] deg"),
        (["specified_angle", "--yaw", "400"], "out of range [0.0, 360.0] deg"),
        (["zoom", "zoomin"], "unknown value 'zoomin'; valid: zoom_in, zoom_out"),
        (["palette", "99"], "unknown value 99"),
        (["gimbal_control", "--pan-speed", "fast"], "'fast' is not a number"),
        (["specified_angle", "--yaw", "45", "--pitch", "3"], "give only one of yaw_deg, pitch_deg"),
        (["specified_angle"], "give axis or one of yaw_deg, pitch_deg, zoom"),
        (["forward", "--s-id", "0x1F"], "forward does not exist for S_ID 0x1F; valid: 0x0F"),
        (["forward", "--s-id", "0x1F", "--component", "gimbal"], "not both"),
        (["forward", "--repeat", "50ms"], "need a destination: --to"),
        (["gimbal_control", "--repeat", "soon", "--to", "can:virtual:x"], "expected an interval"),
        (["recording", "start", "--action", "stop"], "give action once"),
        (["forward", "--to", "udp:1.2.3.4:5"], "expected can:INTERFACE:CHANNEL"),
        ([], "name a command"),
    ],
)
def test_errors_are_one_clear_line(
    capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    code, _, err = run_send(capsys, *args)
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert err.startswith("gimbal-analyzer send: error: ")


def test_unchecked_encodes_out_of_range_values_and_the_decoder_flags_them(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, _ = run_send(capsys, "gimbal_control", "--pan-speed", "150", "--unchecked")
    assert code == 0
    assert "CAN data   0F 04 98 3A" in out
    assert "warning: pan_speed_dps: 150.00 deg/s out of range" in out


def test_every_parameter_of_every_command_has_an_option() -> None:
    parser = argparse.ArgumentParser()
    send.add_arguments(parser)
    for name, rows in BY_NAME.items():
        fields = {f.name for row in rows for f in row.all_fields()}
        args = parser.parse_args([name])
        assert {k.removeprefix("param_") for k in vars(args) if k.startswith("param_")} == fields
    assert len(BY_NAME) == len({c.name for c in COMMANDS})


def test_aliases_drop_the_unit_suffix() -> None:
    fields = {f.name: f for row in COMMANDS for f in row.all_fields()}
    assert send.option_names(fields["pan_speed_dps"]) == ["--pan-speed-dps", "--pan-speed"]
    assert send.option_names(fields["yaw_deg"]) == ["--yaw-deg", "--yaw"]
    assert send.option_names(fields["x_pct"]) == ["--x-pct", "--x"]
    assert send.option_names(fields["delay_s"]) == ["--delay-s", "--delay"]
    assert send.option_names(fields["zoom"]) == ["--zoom"]


def test_list_and_help_come_from_the_table(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_send(capsys, "--list")
    assert code == 0
    for name in BY_NAME:
        assert f"\n{name}  [S_ID/CMD" in "\n" + out
    assert (
        "--pan-speed-dps / --pan-speed: pan speed, positive = right; range [-100.00, 100.00] deg/s"
        in out
    )
    with pytest.raises(SystemExit):
        main(["send", "specified_angle", "--help"])
    out = capsys.readouterr().out
    # Python 3.13's argparse names the value once for all the option's spellings
    assert "--yaw-deg VALUE, --yaw VALUE" in out or "--yaw-deg, --yaw VALUE" in out
    assert "range [-100.0, 60.0] deg" in out


@pytest.mark.parametrize(
    ("text", "seconds"),
    [("50ms", 0.05), ("0.5s", 0.5), ("2s", 2.0), (".25s", 0.25), ("1 ms", 0.001)],
)
def test_intervals(text: str, seconds: float) -> None:
    assert send.parse_interval(text) == pytest.approx(seconds)


@pytest.mark.parametrize("text", ["50", "0.5", ".25"])
def test_an_interval_without_a_unit_is_refused(text: str) -> None:
    with pytest.raises(UsageError, match=f"give the unit, {text}ms or {text}s"):
        send.parse_interval(text)


def test_repeat_without_a_unit_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run_send(capsys, "gimbal_control", "--repeat", "50", "--to", "can:virtual:x")
    assert code == 2
    assert "give the unit, 50ms or 50s" in err


def test_transmits_on_a_can_bus_only_with_to(capsys: pytest.CaptureFixture[str]) -> None:
    spec = f"can:virtual:send-test-{uuid.uuid4().hex[:8]}"
    listener = SimulatedCanLink(parse_link(spec))
    try:
        code, out, _ = run_send(
            capsys, "gimbal_control", "--tilt-speed", "5", "--to", spec,
            "--repeat", "10ms", "--count", "3",
        )  # fmt: skip
        assert code == 0
        assert f"sent 3 time(s) every 10 ms to {spec}" in out
        frames: list[CanFrame] = []
        while len(frames) < 3 and (items := listener.receive(1.0)):
            frames.extend(i for i in items if isinstance(i, CanFrame))
        assert [(f.can_id, f.data.hex()) for f in frames] == [(0xF01, "0f040000f4010000")] * 3
        run_send(capsys, "forward")  # no --to: nothing on the bus
        assert listener.receive(0.2) == []
    finally:
        listener.close()


def test_transmits_tcp_frames_and_reads_the_replies(capsys: pytest.CaptureFixture[str]) -> None:
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    received = bytearray()

    def idu() -> None:
        conn, _ = server.accept()
        with conn:
            conn.settimeout(3)
            while len(received) < 48:
                chunk = conn.recv(1024)
                if not chunk:
                    return
                received.extend(chunk)

    thread = threading.Thread(target=idu, daemon=True)
    thread.start()
    try:
        code, out, _ = run_send(
            capsys, "look_down", "--to", f"tcp:127.0.0.1:{port}", "--count", "2"
        )
        thread.join(3)
    finally:
        server.close()
    assert code == 0
    assert "sent 2 time(s)" in out
    events = ProtocolDecoder().feed(StreamChunk(0.0, bytes(received), "t"))
    assert [(e.topic, e.fields["name"]) for e in events] == [(TOPIC_COMMAND, "look_down")] * 2


def test_unreachable_destination_is_a_source_error(capsys: pytest.CaptureFixture[str]) -> None:
    probe = socket.create_server(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()  # nothing listens there now
    code, _, err = run_send(capsys, "forward", "--to", f"tcp:127.0.0.1:{port}")
    assert code == 1
    assert f"cannot connect to 127.0.0.1:{port}" in err
