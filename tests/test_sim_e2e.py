"""Simulator and analyzer together in real time: python-can virtual bus, loopback TCP, a pty."""

from __future__ import annotations

import os
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest

from analyzer.capture import Capture
from analyzer.pipeline import Batch
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.ids import CONTROL_ID
from analyzer.protocol.types import (
    CRC_MISMATCH,
    DUPLICATE,
    FROM_IDU,
    INCOMPLETE,
    TO_IDU,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    Event,
    StreamChunk,
)
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.faults import FaultConfig
from analyzer.sim.ground import GroundScript, Step
from analyzer.sim.runner import SimulatorRunner
from analyzer.sim.scene import Scene
from analyzer.sim.transports import (
    LinkSpec,
    SimulatedLink,
    open_gimbal_link,
    open_ground_link,
    parse_link,
)
from analyzer.sources import open_source
from tests.platforms import pseudo_terminals

TIMEOUT = 8.0  # generous: these tests wait for a condition, they never assert on timing


class Collect:
    """A capture sink keeping every event."""

    def __init__(self) -> None:
        self._events: list[Event] = []
        self._lock = threading.Lock()

    def handle(self, batch: Batch) -> None:
        with self._lock:
            self._events.extend(batch.events)

    def close(self) -> None:
        pass

    @property
    def events(self) -> list[Event]:
        with self._lock:
            return list(self._events)


def wait_for(condition: Callable[[], Any], timeout: float = TIMEOUT) -> Any:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        result = condition()
        if result:
            return result
        time.sleep(0.05)
    return condition()


@contextmanager
def simulator(spec: LinkSpec, config: SimConfig | None = None) -> Iterator[SimulatorRunner]:
    link = open_gimbal_link(spec)
    runner = SimulatorRunner(SimulatedGimbal(time.monotonic(), config), link, status_every=None)
    runner.keep_received = True
    thread = threading.Thread(target=runner.run, daemon=True)
    thread.start()
    try:
        yield runner
    finally:
        runner.stop()
        thread.join(5)
        link.close()


@contextmanager
def captured(spec: str) -> Iterator[tuple[Collect, Any]]:
    sink = Collect()
    source = open_source(spec)
    capture = Capture(source, [sink])
    capture.start()
    try:
        yield sink, source
    finally:
        capture.stop()
        capture.join(5)


def repeat(link: SimulatedLink, data: bytes, seconds: float) -> None:
    """Send a command every 50 ms for ``seconds`` (gimbal_control must be repeated)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        link.send(CONTROL_ID, data)
        time.sleep(0.05)


def attitude(events: list[Event], test: Callable[[dict[str, Any]], bool]) -> dict[str, Any] | None:
    for event in reversed(events):
        if event.topic == TOPIC_GIMBAL_ATTITUDE and test(event.fields):
            return event.fields
    return None


def diagnostic_kinds(events: list[Event]) -> set[str]:
    return {str(e.fields["kind"]) for e in events if e.topic == TOPIC_DIAGNOSTICS}


def channel() -> str:
    return f"sim-test-{uuid.uuid4().hex[:8]}"


VCAN = os.path.exists("/sys/class/net/vcan0")


@pytest.mark.slow
@pytest.mark.parametrize(
    "bus",
    [
        "virtual",
        pytest.param(
            "socketcan", marks=pytest.mark.skipif(not VCAN, reason="no vcan0 interface here")
        ),
    ],
)
def test_can_bus_commands_are_decoded_and_feedback_follows_them(bus: str) -> None:
    spec = parse_link(f"can:virtual:{channel()}" if bus == "virtual" else "can:socketcan:vcan0")
    with captured(str(spec)) as (sink, _), simulator(spec) as runner:
        ground = open_ground_link(spec)
        try:
            repeat(ground, encode_command("gimbal_control", tilt_speed_dps=20), 0.6)
            assert wait_for(lambda: attitude(sink.events, lambda f: f["pitch_deg"] >= 10))
            commands = [e for e in sink.events if e.topic == TOPIC_COMMAND]
            assert commands and commands[0].fields["name"] == "gimbal_control"
            assert commands[0].fields["tilt_speed_dps"] == 20.0
            assert attitude(sink.events, lambda f: f["control_mode"] == "full_lock")

            ground.send(CONTROL_ID, encode_command("specified_angle", pitch_deg=-30))
            assert wait_for(lambda: attitude(sink.events, lambda f: f["pitch_deg"] == -30.0))
            assert attitude(sink.events, lambda f: f["control_mode"] == "locking")
            assert diagnostic_kinds(sink.events) <= {"link"}
            # The simulator decoded the same commands with the same decoder.
            names = {e.fields["name"] for e in runner.received if e.topic == TOPIC_COMMAND}
            assert names == {"gimbal_control", "specified_angle"}
        finally:
            ground.close()


@pytest.mark.slow
def test_virtual_bus_faults_give_the_matching_diagnostics() -> None:
    spec = parse_link(f"can:virtual:{channel()}")
    faults = FaultConfig(drop=0.2, corrupt=0.2, duplicate=0.2, seed=2)
    with captured(str(spec)) as (sink, _), simulator(spec, SimConfig(faults=faults)) as runner:
        wanted = {INCOMPLETE, CRC_MISMATCH, DUPLICATE}
        assert wait_for(lambda: wanted <= diagnostic_kinds(sink.events)), (
            diagnostic_kinds(sink.events),
            runner.gimbal.faults.counts,
        )


@pytest.mark.slow
def test_loopback_tcp_through_the_proxy_both_directions() -> None:
    with simulator(parse_link("tcp:127.0.0.1:0")) as runner:
        host, port = runner.link.address  # type: ignore[attr-defined]
        with captured(f"proxy:127.0.0.1:0->{host}:{port}") as (sink, proxy):
            proxy_host, proxy_port = proxy.listen_address
            ground = open_ground_link(LinkSpec("tcp", host=proxy_host, port=proxy_port))
            try:
                repeat(ground, encode_command("gimbal_control", tilt_speed_dps=-20), 0.6)
                assert wait_for(lambda: attitude(sink.events, lambda f: f["pitch_deg"] <= -10))
                commands = [e for e in sink.events if e.topic == TOPIC_COMMAND]
                assert commands[0].fields["tilt_speed_dps"] == -20.0
                assert commands[0].fields["direction"] == TO_IDU
                assert attitude(sink.events, lambda f: f["direction"] == FROM_IDU)

                ground.send(CONTROL_ID, encode_command("specified_angle", yaw_deg=30))
                assert wait_for(lambda: attitude(sink.events, lambda f: f["yaw_deg"] == 30.0))
                assert diagnostic_kinds(sink.events) <= {"link"}
            finally:
                ground.close()


def test_loopback_tcp_corruption_is_a_crc_mismatch_on_the_stream() -> None:
    faults = FaultConfig(corrupt=0.3, seed=1)
    with simulator(parse_link("tcp:127.0.0.1:0"), SimConfig(faults=faults)) as runner:
        host, port = runner.link.address  # type: ignore[attr-defined]
        with captured(f"tcp:{host}:{port}") as (sink, _):
            assert wait_for(lambda: CRC_MISMATCH in diagnostic_kinds(sink.events))
            assert wait_for(lambda: attitude(sink.events, lambda f: True))


@pseudo_terminals
def test_serial_gimbal_on_a_pty() -> None:
    master, slave = os.openpty()
    try:
        with simulator(parse_link(f"serial:{os.ttyname(slave)}@115200")):
            os.write(master, wrap_control(encode_command("specified_angle", pitch_deg=-20)))
            decoder = ProtocolDecoder()
            events: list[Event] = []

            def read() -> dict[str, Any] | None:
                data = os.read(master, 4096)
                events.extend(decoder.feed(StreamChunk(time.time(), data, "pty", FROM_IDU)))
                return attitude(events, lambda f: f["pitch_deg"] == -20.0)

            assert wait_for(read)
            assert diagnostic_kinds(events) == set()
    finally:
        os.close(master)
        os.close(slave)


@pytest.mark.slow
def test_scene_plays_a_script_over_tcp() -> None:
    script = GroundScript(
        (Step(0.0, "tracking", {"x": 4096, "y": 4096}), Step(0.1, "look_down")), period=None
    )
    scene = Scene(parse_link("tcp:127.0.0.1:0"), script=script)
    with scene:
        assert wait_for(lambda: scene.gimbal.model.tracking)
        assert wait_for(lambda: scene.gimbal.model.pitch_deg == -90.0)
    assert scene.errors == []
    assert scene.ground.sent == 2


@pytest.mark.parametrize(
    "spec",
    ["bogus", "can:virtual", "tcp:host:port", "serial:", "tcp:", "tcp:70000", "file:x.log"],
)
def test_bad_link_specs_are_usage_errors(spec: str) -> None:
    from analyzer.errors import UsageError

    with pytest.raises(UsageError, match=r"expected can:INTERFACE:CHANNEL"):
        parse_link(spec)


def test_link_specs() -> None:
    assert parse_link("tcp:2000") == LinkSpec("tcp", host="127.0.0.1", port=2000)
    assert parse_link("tcp:[::1]:2001") == LinkSpec("tcp", host="::1", port=2001)
    assert str(parse_link("can:slcan:/dev/ttyACM0@1000000")) == "can:slcan:/dev/ttyACM0@1000000"
    assert parse_link("serial:/dev/ttyUSB0").rate == 115200
