"""The Python API's ``Listener`` on python-can's own virtual bus, the simulated gimbal on the
other end: commands sent with ``can_message``, its feedback decoded in the notifier's thread."""

from __future__ import annotations

import threading
import uuid
from collections.abc import Callable
from contextlib import AbstractContextManager

import can
import pytest

from analyzer import Event, Listener, can_message, status_message
from analyzer.sim.runner import SimulatorRunner
from analyzer.sim.transports import parse_link
from tests.test_sim_e2e import simulator, wait_for


def gimbal_on(channel: str) -> AbstractContextManager[SimulatorRunner]:
    """The simulated gimbal in real time on the virtual bus ``channel``."""
    return simulator(parse_link(f"can:virtual:{channel}"))


class Seen:
    """The callback: every event, kept for the test (the notifier's thread appends)."""

    def __init__(self) -> None:
        self.events: list[Event] = []
        self.lock = threading.Lock()

    def __call__(self, event: Event) -> None:
        with self.lock:
            self.events.append(event)

    def attitude(self, test: Callable[[dict[str, object]], bool]) -> dict[str, object] | None:
        with self.lock:
            found = [
                e.fields for e in self.events if e.topic == "/gimbal/attitude" and test(e.fields)
            ]
        return found[-1] if found else None


@pytest.mark.slow
def test_the_listener_decodes_the_simulated_gimbals_feedback_in_the_notifier() -> None:
    channel = f"api-{uuid.uuid4().hex[:8]}"
    seen = Seen()
    listener = Listener(seen)
    with gimbal_on(channel) as gimbal, can.Bus(interface="virtual", channel=channel) as bus:
        notifier = can.Notifier(bus, [listener])
        try:
            bus.send(can_message("specified_angle", pitch_deg=-30))
            assert wait_for(lambda: seen.attitude(lambda f: f["pitch_deg"] == -30.0))
            bus.send(status_message("gps", latitude_deg=31.1234567, longitude_deg=118.1234567))
            bus.send(can_message("specified_angle", yaw_deg=45, coordinate_system="airframe"))
            assert wait_for(lambda: seen.attitude(lambda f: f["motor_yaw_deg"] == 45.0))
        finally:
            notifier.stop()
    # the gimbal got what the API encoded; the listener heard only the gimbal (a virtual
    # bus does not give a bus its own messages back)
    received = [
        e.fields.get("name") or e.topic for e in gimbal.received if e.topic != "/diagnostics"
    ]
    assert received == ["specified_angle", "/uav/gps", "specified_angle"]
    assert {e.topic for e in seen.events} <= {"/gimbal/attitude", "/gimbal/ranging", "/diagnostics"}
    assert all(e.source == channel for e in seen.events)
    assert listener.errors == 0


@pytest.mark.slow
def test_an_exception_in_the_callback_never_stops_the_notifier(
    caplog: pytest.LogCaptureFixture,
) -> None:
    channel = f"api-{uuid.uuid4().hex[:8]}"
    seen = Seen()
    handled: list[Exception] = []

    def clumsy(event: Event) -> None:
        seen(event)
        if len(seen.events) % 2:
            raise ValueError(f"the integrator's bug, event {len(seen.events)}")

    def broken(event: Event) -> None:
        raise RuntimeError("always")

    listener = Listener(clumsy, error_handler=handled.append)
    quiet = Listener(broken)  # no handler: logged, and the notifier goes on all the same
    with gimbal_on(channel), can.Bus(interface="virtual", channel=channel) as bus:
        notifier = can.Notifier(bus, [listener, quiet])
        try:
            assert wait_for(lambda: len(seen.events) >= 8)
            bus.send(can_message("specified_angle", pitch_deg=20))
            assert wait_for(lambda: seen.attitude(lambda f: f["pitch_deg"] == 20.0))
            assert notifier.exception is None  # and it went on: the attitude above came after
        finally:
            notifier.stop()
    assert listener.errors == len(handled) > 0 and quiet.errors > 0
    assert str(handled[0]).startswith("the integrator's bug")
    assert str(quiet.last_error) == "always"
    assert "gimbal-analyzer Listener: always" in caplog.text


@pytest.mark.filterwarnings("ignore::pytest.PytestUnhandledThreadExceptionWarning")
def test_what_the_listener_spares_the_notifier_from() -> None:
    """A python-can listener that lets its callback's exception out stops the notifier's
    thread: the failure the Listener above is tested against."""

    class Naive(can.Listener):
        def on_message_received(self, msg: can.Message) -> None:
            raise ValueError("the integrator's bug")

    channel = f"api-{uuid.uuid4().hex[:8]}"
    with (
        can.Bus(interface="virtual", channel=channel) as bus,
        can.Bus(interface="virtual", channel=channel) as other,
    ):
        notifier = can.Notifier(bus, [Naive()], timeout=0.05)
        try:
            other.send(can_message("forward"))
            assert wait_for(lambda: notifier.exception is not None)
        finally:
            notifier.stop()
