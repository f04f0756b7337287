"""A simulated session in virtual time: script + gimbal -> decoded events; no IO, no waiting."""

from __future__ import annotations

from analyzer.protocol.decoder import Decoder
from analyzer.protocol.ids import CONTROL_ID
from analyzer.protocol.types import CanFrame, Event
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.ground import GroundScript, Step

TICK_S = 0.01  # the virtual clock's step


def run_offline(
    steps: tuple[Step, ...],
    duration: float,
    config: SimConfig | None = None,
    *,
    start: float = 0.0,
    channel: str = "sim",
) -> tuple[list[CanFrame], list[Event]]:
    """Play ``steps`` against a simulated gimbal for ``duration`` seconds.

    Returns the CAN frames on the bus (commands and everything the gimbal sent) and the
    events the decoder made of them, as a capture of that bus would give them.
    """
    script = GroundScript(steps, period=None)
    gimbal = SimulatedGimbal(start, config)
    decoder = Decoder()
    frames: list[CanFrame] = []
    events: list[Event] = []
    for tick in range(round(duration / TICK_S) + 1):
        now = start + tick * TICK_S
        for data in script.due(now - start):
            frame = CanFrame(now, CONTROL_ID, data, channel=channel)
            frames.append(frame)
            for event in decoder.feed_can(frame):
                events.append(event)
                gimbal.handle(event, now)
        for can_id, data in gimbal.poll(now):
            frame = CanFrame(now, can_id, data, channel=channel)
            frames.append(frame)
            events.extend(decoder.feed_can(frame))
    events.extend(decoder.close(start + duration))
    return frames, events
