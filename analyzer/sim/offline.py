"""A simulated session in virtual time: script + gimbal -> decoded events; no IO, no waiting."""

from __future__ import annotations

from collections.abc import Callable

from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.ids import CONTROL_ID
from analyzer.protocol.types import FROM_IDU, TO_IDU, CanFrame, Event, StreamChunk
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.ground import GroundScript, Step
from analyzer.sim.transports import to_stream

TICK_S = 0.01  # the virtual clock's step

# (time, CAN ID, data, sent by the ground station) -> what a capture of the link holds.
Wire = Callable[[float, int, bytes, bool], CanFrame | StreamChunk]
# Called at every tick with the time and the gimbal (the simulated camera looks at it).
Watch = Callable[[float, SimulatedGimbal], None]


def _play(
    steps: tuple[Step, ...],
    duration: float,
    config: SimConfig | None,
    start: float,
    wire: Wire,
    watch: Watch | None = None,
) -> tuple[list[CanFrame | StreamChunk], list[Event]]:
    script = GroundScript(steps, period=None)
    gimbal = SimulatedGimbal(start, config)
    decoder = ProtocolDecoder()
    items: list[CanFrame | StreamChunk] = []
    events: list[Event] = []
    for tick in range(round(duration / TICK_S) + 1):
        now = start + tick * TICK_S
        for data in script.due(now - start):
            item = wire(now, CONTROL_ID, data, True)
            items.append(item)
            for event in decoder.feed(item):
                events.append(event)
                gimbal.handle(event, now)
        for can_id, data in gimbal.poll(now):
            item = wire(now, can_id, data, False)
            items.append(item)
            events.extend(decoder.feed(item))
        if watch is not None:
            watch(now, gimbal)
    events.extend(decoder.close(start + duration))
    return items, events


def run_offline(
    steps: tuple[Step, ...],
    duration: float,
    config: SimConfig | None = None,
    *,
    start: float = 0.0,
    channel: str = "sim",
    watch: Watch | None = None,
) -> tuple[list[CanFrame], list[Event]]:
    """Play ``steps`` against a simulated gimbal on a CAN bus for ``duration`` seconds.

    Returns the CAN frames on the bus (commands and everything the gimbal sent) and the
    events the decoder made of them, as a capture of that bus would give them. ``watch``
    is called at every tick after the gimbal moved (the simulated camera).
    """

    def on_bus(now: float, can_id: int, data: bytes, _: bool) -> CanFrame:
        return CanFrame(now, can_id, data, channel=channel)

    items, events = _play(steps, duration, config, start, on_bus, watch)
    return [i for i in items if isinstance(i, CanFrame)], events


def run_offline_stream(
    steps: tuple[Step, ...],
    duration: float,
    config: SimConfig | None = None,
    *,
    start: float = 0.0,
    source: str = "tcp:127.0.0.1:50312-127.0.0.1:2000",
) -> tuple[list[StreamChunk], list[Event]]:
    """The same session on the IDU's TCP port (or the UART): commands in 0x0A frames, the
    feedback as its byte stream, anything else in 0x0B frames, as the simulator's TCP link
    sends them. Returns the chunks each side wrote and the events decoded from them."""

    def on_link(now: float, can_id: int, data: bytes, from_ground: bool) -> StreamChunk:
        direction = TO_IDU if from_ground else FROM_IDU
        return StreamChunk(now, to_stream(can_id, data), source=source, direction=direction)

    items, events = _play(steps, duration, config, start, on_link)
    return [i for i in items if isinstance(i, StreamChunk)], events
