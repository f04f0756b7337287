"""The demo's scripted ground station: a timed, looping list of commands sent on a link."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from analyzer.protocol.codec import encode_command
from analyzer.protocol.ids import CONTROL_ID
from analyzer.sim.pilot import Stick
from analyzer.sim.transports import SimulatedLink

REPEAT_S = 0.05  # gimbal_control is repeated every 50 ms, as the document recommends
EPSILON = 1e-6  # times are sums of floats: compare with a little slack


@dataclass(frozen=True)
class Step:
    """Send command ``name`` at ``at`` seconds; with ``until``, repeat it every 50 ms.

    With ``stick`` (a gimbal_control), the speeds are a pilot's stick movement from ``at``
    to ``until`` instead of ``params``' fixed ones, followed by the stick's centred time
    with 0, 0 sent; ``params`` may still name the ``component``."""

    at: float
    name: str
    params: dict[str, Any] = field(default_factory=dict)
    until: float | None = None
    stick: Stick | None = None

    def data(self) -> bytes:
        return self.data_at(self.at)

    def data_at(self, t: float) -> bytes:
        """The command's bytes when sent at ``t`` seconds (a stick's speeds change)."""
        stick = self.stick
        if stick is None or self.until is None:
            return encode_command(self.name, **self.params)
        pan, tilt = stick.speeds(t - self.at, self.until - self.at)
        return encode_command(self.name, **self.params, pan_speed_dps=pan, tilt_speed_dps=tilt)

    @property
    def stream_end(self) -> float | None:
        """When its repeats end: ``until``, and a stick's centred time after it."""
        if self.until is None:
            return None
        return self.until + (self.stick.centred_s if self.stick is not None else 0.0)


DEMO_SCRIPT: tuple[Step, ...] = (
    Step(0.2, "forward"),
    Step(0.5, "gimbal_control", {"tilt_speed_dps": -20}, until=2.0),
    Step(2.2, "gimbal_control", {"pan_speed_dps": 25}, until=3.4),
    Step(3.6, "specified_angle", {"yaw_deg": 90}),
    Step(4.8, "specified_angle", {"pitch_deg": -45}),
    Step(5.5, "zoom", {"action": "zoom_in"}),
    Step(6.5, "zoom", {"action": "stop"}),
    Step(7.0, "tracking", {"x": 5000, "y": 3500, "width": 480, "height": 320}),
    Step(7.6, "snapshot", {"mode": "single"}),
    Step(8.0, "recording", {"action": "start"}),
    Step(9.0, "tracking_stop"),
    Step(9.3, "specified_angle", {"zoom": 1}),
    Step(9.6, "look_down"),
    Step(11.5, "recording", {"action": "stop"}),
    Step(12.0, "palette", {"palette": "iron_red"}),
    Step(12.5, "focus", {"action": "auto_focus"}),
    Step(13.0, "forward"),
)
DEMO_PERIOD = 15.0  # the script starts over after this many seconds
STICK_PEAK = 1.3  # a stick movement peaks above the speed a fixed step asks (its mean is less)
STICK_CENTRED_S = 0.15  # zeros sent after each movement (before the next command comes)


def pilot_script(steps: tuple[Step, ...] = DEMO_SCRIPT) -> tuple[Step, ...]:
    """``steps`` with each repeated gimbal_control played on a pilot's stick: the same
    direction and time, smooth with a reading's noise, speeds changing in every command,
    and a short centred stretch of zeros after it."""
    out: list[Step] = []
    for n, step in enumerate(steps):
        if step.name == "gimbal_control" and step.until is not None and step.stick is None:
            params = dict(step.params)
            pan = float(params.pop("pan_speed_dps", 0.0)) * STICK_PEAK
            tilt = float(params.pop("tilt_speed_dps", 0.0)) * STICK_PEAK
            stick = Stick(pan, tilt, centred_s=STICK_CENTRED_S, seed=n)
            step = Step(step.at, step.name, params, until=step.until, stick=stick)
        out.append(step)
    return tuple(out)


class GroundScript:
    """Which command frames are due ``elapsed`` seconds after the start; sans-IO."""

    def __init__(self, steps: tuple[Step, ...] = DEMO_SCRIPT, period: float | None = DEMO_PERIOD):
        self.steps = tuple(sorted(steps, key=lambda s: s.at))
        self.period = period
        self._data = [s.data() for s in self.steps]
        self._round = 0
        self._index = 0
        # (next time, until, the round's start, the step's index) of the steps repeating
        self._repeat: list[tuple[float, float, float, int]] = []

    def due(self, elapsed: float) -> list[bytes]:
        out: list[bytes] = []
        while True:
            base = self._round * (self.period or 0.0)
            if self._index >= len(self.steps):
                if not self.period:
                    break
                self._round += 1
                self._index = 0
                continue
            step = self.steps[self._index]
            if base + step.at > elapsed + EPSILON:
                break
            out.append(self._data[self._index])
            end = step.stream_end
            if end is not None:
                start = base + step.at
                self._repeat.append((start + REPEAT_S, base + end, base, self._index))
            self._index += 1
        still: list[tuple[float, float, float, int]] = []
        for when, until, base, index in self._repeat:
            if when <= elapsed + EPSILON and when <= until + EPSILON:
                step = self.steps[index]
                out.append(self._data[index] if step.stick is None else step.data_at(when - base))
                when = max(when + REPEAT_S, elapsed)
            if when <= until + EPSILON:
                still.append((when, until, base, index))
        self._repeat = still
        return out

    def next_due(self, elapsed: float) -> float:
        """Seconds until the next frame could be due (at most one repeat interval)."""
        if self._repeat:
            return max(0.0, min(r[0] for r in self._repeat) - elapsed)
        return REPEAT_S


class GroundStation:
    """Plays a GroundScript on a link in real time until stopped."""

    def __init__(
        self,
        link: SimulatedLink,
        script: GroundScript | None = None,
        *,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.link = link
        self.script = script or GroundScript()
        self.clock = clock
        self.sent = 0
        self._stop = threading.Event()

    def stop(self) -> None:
        self._stop.set()

    def run(self, duration: float | None = None) -> None:
        start = self.clock()
        while not self._stop.is_set():
            elapsed = self.clock() - start
            if duration is not None and elapsed >= duration:
                break
            for data in self.script.due(elapsed):
                self.link.send(CONTROL_ID, data)
                self.sent += 1
            # Read (and drop) what the bus carries, so no receive queue grows.
            self.link.receive(min(REPEAT_S, self.script.next_due(self.clock() - start)))
