"""The sans-IO ``Decoder`` target: an input is a script of CAN frames, stream bytes and time.

Nothing the Decoder is fed may raise: its events (every one printed as ``decode``
prints it, text and JSON) and ``analyze`` of them must come out whatever the bytes.
A script is a run of steps, each a first byte (its low two bits say what it is) and
its operands; a script cut short ends where its bytes end:

- ``0``: a CAN frame on one of the protocol's IDs (byte: which, byte: length, data);
- ``1``: a CAN frame on any ID (4 bytes little-endian: bit 31 standard, the rest the
  ID; byte: length, data);
- ``2``: stream bytes (2 bytes: length; byte: which stream and direction; data);
- ``3``: time passes (2 bytes: milliseconds, a negative number goes back) and the
  decoder's ``tick`` runs.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass

from analyzer.protocol.ids import PROTOCOL_IDS
from analyzer.protocol.types import CanFrame

CAN, ANY_CAN, STREAM, TIME = range(4)
IDS = tuple(sorted(PROTOCOL_IDS))
STREAMS = (("stream", ""), ("tcp", "idu_to_gs"), ("tcp", "gs_to_idu"), ("uart", ""))
START = 1_715_680_800.0  # the samples' first second
STEP_S = 0.001  # the time between two frames when the script says nothing
_ID = struct.Struct("<I")
_LENGTH = struct.Struct("<H")
_MILLISECONDS = struct.Struct("<h")


@dataclass
class Step:
    """One step of a script: ``kind`` and what it carries."""

    kind: int
    can_id: int = 0
    extended: bool = True
    data: bytes = b""
    stream: int = 0
    step_s: float = 0.0


def steps(script: bytes) -> Iterator[Step]:
    """The steps of a script, as far as its bytes go."""
    at = 0
    end = len(script)
    while at < end:
        head = script[at]
        at += 1
        kind = head & 3
        if kind == CAN and at + 2 <= end:
            can_id = IDS[script[at] % len(IDS)]
            size = script[at + 1] % 65  # up to a CAN FD frame's 64 bytes
            yield Step(CAN, can_id, data=script[at + 2 : at + 2 + size])
            at += 2 + size
        elif kind == ANY_CAN and at + 5 <= end:
            (word,) = _ID.unpack_from(script, at)
            size = script[at + 4] % 65
            extended = not word & 0x8000_0000
            can_id = word & (0x1FFF_FFFF if extended else 0x7FF)
            yield Step(ANY_CAN, can_id, extended, script[at + 5 : at + 5 + size])
            at += 5 + size
        elif kind == STREAM and at + 3 <= end:
            (size,) = _LENGTH.unpack_from(script, at)
            stream = script[at + 2] % len(STREAMS)
            yield Step(STREAM, data=script[at + 3 : at + 3 + size], stream=stream)
            at += 3 + size
        elif kind == TIME and at + 2 <= end:
            (milliseconds,) = _MILLISECONDS.unpack_from(script, at)
            yield Step(TIME, step_s=milliseconds / 1000)
            at += 2
        else:
            return


def run(script: bytes) -> None:
    """Feed a script to a Decoder; print and analyse what comes out."""
    from analyzer.api.analysis import analyze
    from analyzer.api.decoding import Decoder
    from analyzer.commands.decode import make_printer

    decoder = Decoder(other_frames=bool(script) and script[0] & 0x80 != 0)
    events = []
    now = START
    for step in steps(script):
        now += STEP_S
        if step.kind == TIME:
            now += step.step_s
            events += decoder.tick(now)
        elif step.kind == STREAM:
            source, direction = STREAMS[step.stream]
            events += decoder.feed_stream(step.data, now, source=source, direction=direction)
        else:
            events += decoder.feed_can(step.can_id, step.data, now, extended=step.extended)
    events += decoder.close()
    for printer in (make_printer(True, False), make_printer(False, False)):
        for event in events:
            printer(event)
    list(analyze(events))


def script_of(frames: list[CanFrame], stream: bytes = b"") -> bytes:
    """A script that feeds ``frames`` (with their time steps) and then ``stream``."""
    out = bytearray()
    last = frames[0].time if frames else START
    for frame in frames:
        gap = round((frame.time - last) * 1000)
        last = frame.time
        if gap > 1:
            out += bytes([TIME]) + _MILLISECONDS.pack(max(-32768, min(32767, gap)))
        if frame.can_id in PROTOCOL_IDS and frame.extended and len(frame.data) <= 64:
            out += bytes([CAN, IDS.index(frame.can_id), len(frame.data)]) + frame.data
        else:
            word = frame.can_id | (0 if frame.extended else 0x8000_0000)
            out += bytes([ANY_CAN]) + _ID.pack(word) + bytes([len(frame.data) % 65])
            out += frame.data[:64]
    for at in range(0, len(stream), 200):  # the stream in pieces, as a socket gives it
        piece = stream[at : at + 200]
        out += bytes([STREAM]) + _LENGTH.pack(len(piece)) + bytes([at // 200 % 2]) + piece
    return bytes(out)


def seeds() -> list[bytes]:
    """The flight sample's first frames; the UART sample; both at once."""
    from fuzz.seeds import SAMPLES, seed_frames

    frames = seed_frames()
    uart = (SAMPLES / "uart-dump.bin").read_bytes()
    return [script_of(frames), script_of([], uart), script_of(frames[:10], uart[:300])]
