"""The response analysis looks at each attitude sample a bounded number of times, whatever
the length of the flight: no judgement scans the flight from its start (counted, not timed).

The samples kept are those a pending judgement can still need (a window as long as the
time allowed), so the work per command and the memory do not grow with the input.
"""

from __future__ import annotations

import random

import pytest

from analyzer.analysis.response import ResponseAnalyzer, Settings
from analyzer.analysis.sample_window import SampleWindow
from analyzer.analysis.samples import Sample
from analyzer.protocol.types import TOPIC_COMMAND, TOPIC_GIMBAL_ATTITUDE, Event

T0 = 1_700_000_000.0
FEEDBACK_HZ = 40  # the dense bus: an attitude message every 25 ms


def attitude(t: float, pitch: float, yaw: float) -> Event:
    fields = {"pitch_deg": pitch, "yaw_deg": yaw, "motor_yaw_deg": yaw - 180, "tracking": False}
    return Event(TOPIC_GIMBAL_ATTITUDE, t, "can0", fields)


def command(t: float, name: str, **fields: object) -> Event:
    return Event(TOPIC_COMMAND, t, "can0", {"name": name, **fields})


class Pilot:
    """A pilot's stick: movements of 0.5 to 3 s at random peak speeds (the values change in
    every command), then 0.5 to 2 s centred, the ground station sending zeros."""

    def __init__(self, rng: random.Random) -> None:
        self.rng = rng
        self.until = 0.0
        self.centred = True
        self.peak = (0.0, 0.0)

    def speeds(self, t: float) -> tuple[float, float]:
        rng = self.rng
        if t >= self.until:
            self.centred = not self.centred
            self.until = t + (rng.uniform(0.5, 2) if self.centred else rng.uniform(0.5, 3))
            self.peak = (rng.uniform(-60, 60), rng.uniform(-60, 60))
        if self.centred:
            return 0.0, 0.0
        return tuple(p + rng.gauss(0, 0.03) for p in self.peak)  # type: ignore[return-value]


def flight(seconds: float, every: int, seed: int = 1, pilot: bool = True) -> list[Event]:
    """A moving gimbal, a pilot's stick 9 times per feedback message (``pilot``; else the
    stick held off centre at random speeds all the time) and, every ``every`` messages, a
    target command (specified_angle, look_down or tracking)."""
    rng = random.Random(seed)
    stick = Pilot(random.Random(seed + 1))
    events: list[Event] = []
    pitch, yaw = -30.0, 180.0
    targets = [
        lambda t: command(t, "specified_angle", axis="pitch", pitch_deg=rng.uniform(-90, 0)),
        lambda t: command(t, "specified_angle", axis="yaw", yaw_deg=rng.uniform(0, 360)),
        lambda t: command(t, "look_down"),
        lambda t: command(t, "tracking", x=1, y=1),
        lambda t: command(t, "tracking_stop"),
    ]
    for n in range(int(seconds * FEEDBACK_HZ)):
        t = T0 + n / FEEDBACK_HZ
        pitch = max(-90.0, min(30.0, pitch + rng.uniform(-3, 3)))
        yaw = (yaw + rng.uniform(-5, 5)) % 360
        events.append(attitude(t, pitch, yaw))
        for k in range(9):
            if pilot:
                pan, tilt = stick.speeds(t + 0.001 * (k + 1))
            else:
                pan, tilt = rng.uniform(-100, 100), rng.uniform(-100, 100)
            events.append(
                command(
                    t + 0.001 * (k + 1), "gimbal_control", pan_speed_dps=pan, tilt_speed_dps=tilt
                )
            )
        if every and n % every == 0:
            events.append(targets[n // every % len(targets)](t + 0.0125))
    return events


def run(events: list[Event], settings: Settings | None = None) -> tuple[ResponseAnalyzer, int]:
    """The analyzer after the events, and the most samples it kept at any time."""
    analyzer = ResponseAnalyzer(settings)
    kept = 0
    for event in events:
        analyzer.feed(event)
        kept = max(kept, len(analyzer.samples))
    analyzer.close()
    return analyzer, kept


@pytest.mark.slow
def test_samples_examined_per_command_do_not_grow_with_the_flight() -> None:
    per_command = []
    for seconds in (20.0, 80.0):
        events = flight(seconds, every=0)
        analyzer, kept = run(events)
        commands = sum(1 for e in events if e.topic == TOPIC_COMMAND)
        per_command.append(analyzer.samples.examined / commands)
        # A movement (3 s at most) and its watch after it (2.5 s): never the flight.
        assert kept <= 7 * FEEDBACK_HZ
    # A scan of the kept history would examine thousands of samples per command.
    assert max(per_command) <= 1
    assert per_command[1] <= per_command[0] * 1.2


@pytest.mark.slow
def test_a_stick_held_off_centre_all_flight_is_judged_a_minute_at_a_time() -> None:
    """No movement is kept open without end: one held for the whole flight is judged in
    pieces of MAX_MOVEMENT_S, so the samples and commands kept stay bounded."""
    from analyzer.analysis.streams import MAX_MOVEMENT_S

    for seconds in (70.0, 190.0):
        events = flight(seconds, every=0, pilot=False)
        analyzer = ResponseAnalyzer()
        kept = 0
        rates = []
        for event in events:
            rates += [f for f in analyzer.feed(event) if f.fields["check"] == "rate"]
            kept = max(kept, len(analyzer.samples))
        rates += [f for f in analyzer.close() if f.fields["check"] == "rate"]
        assert len(rates) == int(seconds // MAX_MOVEMENT_S) + 1
        assert kept <= (MAX_MOVEMENT_S + 3) * FEEDBACK_HZ


def test_target_commands_look_only_at_their_time_allowed() -> None:
    allowed = 5.0
    per_command = []
    for seconds in (20.0, 80.0):
        events = flight(seconds, every=20)  # a target command every half second
        analyzer, kept = run(events, Settings(time_allowed_s=allowed))
        commands = sum(1 for e in events if e.topic == TOPIC_COMMAND)
        per_command.append(analyzer.samples.examined / commands)
        # The window: the samples of the time allowed (and one before), never the flight.
        assert kept <= allowed * FEEDBACK_HZ + 2
    assert per_command[1] <= per_command[0] * 1.2


def test_the_window_forgets_what_no_judgement_needs() -> None:
    window = SampleWindow()
    for n in range(10_000):
        window.append(Sample(T0 + n, 0.0, 0.0, 0.0, False, 0))
        window.forget_before(T0 + n - 10)
    assert len(window) == 11 and window.before(T0 + 9_995.5) == Sample(
        T0 + 9_995, 0, 0, 0, False, 0
    )
    assert [s.time - T0 for s in window.between(T0 + 9_997, T0 + 9_999)] == [9_998, 9_999]
    assert window.examined <= 10


def test_a_clock_that_jumps_back_keeps_the_history_and_scans_it() -> None:
    window = SampleWindow(history=100)
    times = [*range(50), 10, *range(50, 300)]  # one sample from the past, after 49
    for n, t in enumerate(times):
        window.append(Sample(T0 + t, float(n), 0.0, 0.0, False, 0))
        window.forget_before(T0 + t)
        if 50 <= n < 149:  # nothing forgotten early while the odd pair is kept
            assert len(window) == n - 48
            assert [s.pitch for s in window.between(T0 + 9, T0 + 11)] == [50.0]
    assert len(window) == 1  # it has left the history: forgetting goes on
