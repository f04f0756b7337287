"""An integrator's script using every public name of ``analyzer``, as a user writes it.

``tests/test_api_package.py`` type-checks it with ``mypy --strict`` (so the package's
public signatures must be real types) and runs it.
"""

from __future__ import annotations

import os
import tempfile
from collections import Counter
from collections.abc import Iterator

import can

import analyzer
from analyzer import (
    COMMANDS,
    Decoder,
    Event,
    Finding,
    Listener,
    Recording,
    analyze,
    can_message,
    encode,
    read,
    status_message,
    tcp_frame,
    text_messages,
)


def commands_to_send() -> list[bytes]:
    data: bytes = encode("gimbal_control", pan_speed_dps=-5.0, tilt_speed_dps=2)
    angle: bytes = encode("specified_angle", axis="yaw", yaw_deg=45, coordinate_system="geodetic")
    palette: bytes = encode("palette", component="dual_sensor", palette="iron_red")
    frame: bytes = tcp_frame("look_down")
    return [data, angle, palette, frame]


def aircraft_status() -> list[can.Message]:
    messages: list[can.Message] = [
        can_message("snapshot", mode="single"),
        status_message("gps", latitude_deg=31.1234567, longitude_deg=118.1234567),
        status_message("altitude", altitude_m=120.5),
        status_message("attitude", pitch_deg=1.5, roll_deg=-2.0, yaw_deg=90.0),
        status_message("text", text="armed"),
    ]
    return messages + text_messages("Mission: orbit 150 m")


def decode_bus(messages: list[can.Message]) -> list[Event]:
    decoder = Decoder(other_frames=False)
    events: list[Event] = []
    for message in messages:
        events += decoder.feed_message(message)
    events += decoder.feed_can(0x00000F01, encode("forward"), 1.5, channel="can0")
    events += decoder.feed_stream(tcp_frame("zoom", action="zoom_in"), timestamp=2.0)
    return events + decoder.close()


def topics_of(path: str) -> Counter[str]:
    events: Iterator[Event] = read(path, format=None)
    return Counter(event.topic for event in events)


def problems(path: str) -> list[str]:
    findings: Iterator[Finding] = analyze(path, tolerance_deg=2.0, time_allowed_s=8.0)
    return [f"{f.time:.3f} {f.command} {f.check}: {f.verdict}" for f in findings]


def commands_recorded(path: str) -> int:
    recording = Recording(path)
    wanted: list[str] = [t for t in recording.topics() if t.startswith("/gimbal")]
    for event in recording.events(wanted):
        assert isinstance(event.to_dict()["time"], float)
    table = recording.table("/gimbal/command")  # a pyarrow.Table
    rows: int = table.num_rows
    return rows


def ranges() -> dict[str, tuple[float | None, float | None]]:
    return {
        f"{command.name}.{parameter.name}": (parameter.minimum, parameter.maximum)
        for command in COMMANDS
        for parameter in command.parameters
        if parameter.unit == "deg"
    }


def listen(bus: can.BusABC) -> can.Notifier:
    seen: list[Event] = []
    listener = Listener(seen.append, error_handler=lambda exc: print(exc))
    return can.Notifier(bus, [listener])


def main(sample: str) -> None:
    assert len(commands_to_send()) == 4
    events = decode_bus(aircraft_status())
    assert [e.topic for e in events][:3] == ["/gimbal/command", "/uav/gps", "/uav/altitude"]
    assert topics_of(sample)["/gimbal/command"] > 0
    assert problems(sample)
    with tempfile.TemporaryDirectory() as folder:
        recording = os.path.join(folder, "flight.mcap")
        from analyzer.cli import main as command_line

        assert command_line(["convert", sample, "-o", recording, "-q"]) == 0
        assert commands_recorded(recording) == topics_of(sample)["/gimbal/command"]
    assert ranges()["specified_angle.yaw_deg"] == (0.0, 360.0)
    assert analyzer.__version__


if __name__ == "__main__":
    main("samples/flight-candump.log")
