"""``Decoder``: the sans-IO decoder for integrators: CAN frames or stream bytes in, events out."""

from __future__ import annotations

from typing import TYPE_CHECKING

from analyzer.protocol.can_message import frame_from_message
from analyzer.protocol.decoder import ProtocolDecoder as ProtocolDecoder
from analyzer.protocol.types import CanFrame, Event, StreamChunk

if TYPE_CHECKING:
    import can

__all__ = ["Decoder"]


class Decoder:
    """Decodes the protocol from CAN frames and TCP / UART bytes; no IO, no clock.

    ``feed_can`` takes one CAN frame and returns the events it completes: a command at
    once, the gimbal's feedback once its four segments are in (CRC checked), a text
    message at its end frame. ``feed_stream`` takes bytes of a TCP or UART stream split
    anywhere. Nothing here raises on bytes: damage (a CRC mismatch, a lost segment,
    garbage between frames) comes back as ``/diagnostics`` events. ``close()`` reports
    what is still incomplete at the end of the input. This is the decoder every command
    of the command line runs; ``other_frames=True`` also gives the frames of other
    devices as ``/can/other`` events (``decode --raw``).

    >>> from analyzer import Decoder, encode
    >>> decoder = Decoder()
    >>> [event] = decoder.feed_can(0x00000F01, encode("look_down"), timestamp=12.5)
    >>> event.topic, event.time, event.fields["name"]
    ('/gimbal/command', 12.5, 'look_down')

    A stream split in the middle of a frame gives the event when its last byte comes:

    >>> from analyzer import tcp_frame
    >>> frame = tcp_frame("specified_angle", pitch_deg=-45)
    >>> decoder.feed_stream(frame[:10], timestamp=13.0)
    []
    >>> [event] = decoder.feed_stream(frame[10:], timestamp=13.01)
    >>> event.fields["pitch_deg"], event.fields["transport"]
    (-45.0, 'stream')
    >>> [e.fields["kind"] for e in decoder.feed_stream(b"noise", 14.0) + decoder.close()]
    ['garbage']
    """

    def __init__(self, *, other_frames: bool = False) -> None:
        self._decoder = ProtocolDecoder(emit_other=other_frames)

    def feed_can(
        self,
        can_id: int,
        data: bytes | bytearray | memoryview,
        timestamp: float,
        channel: str | None = None,
        *,
        extended: bool = True,
    ) -> list[Event]:
        """One CAN data frame -> the events it completes (often none: a feedback segment).

        ``timestamp`` in seconds (Unix time or from any start); ``channel`` names the bus
        (each channel is reassembled apart; the events' ``source``, default ``can``).
        A standard (11-bit) frame on a protocol ID is decoded with a warning.
        """
        frame = CanFrame(float(timestamp), int(can_id), bytes(data), extended, channel or "")
        return self._decoder.feed_can(frame)

    def feed_message(self, message: can.Message, channel: str | None = None) -> list[Event]:
        """A python-can ``Message`` (from ``bus.recv()`` or a log reader) -> events;
        remote and error frames included (an error frame gives a ``bus_error``)."""
        return self._decoder.feed_can(frame_from_message(message, channel))

    def feed_stream(
        self,
        data: bytes | bytearray | memoryview,
        timestamp: float,
        *,
        source: str = "stream",
        direction: str = "",
    ) -> list[Event]:
        """Bytes of a TCP / UART stream (frames of chapter 3, split anywhere) -> events.

        Each ``source`` (and ``direction``: ``gs_to_idu`` / ``idu_to_gs``) is framed
        apart; events of a direction carry it as a field.
        """
        chunk = StreamChunk(float(timestamp), bytes(data), source, direction)
        return self._decoder.feed_stream(chunk)

    def tick(self, now: float) -> list[Event]:
        """Live input: diagnostics for partial messages that waited too long by ``now``."""
        return self._decoder.tick(float(now))

    def close(self) -> list[Event]:
        """The end of the input: whatever is still incomplete, as diagnostics."""
        return self._decoder.close()
