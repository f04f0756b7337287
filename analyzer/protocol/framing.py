"""TCP / UART byte-stream framing of chapter 3: find frames, resynchronise, check CRCs."""

from __future__ import annotations

from dataclasses import dataclass

from analyzer.protocol.crc import check_crc, crc16, crc_bytes
from analyzer.protocol.feedback import FRAME_SIZES
from analyzer.protocol.ids import (
    FEEDBACK_MESSAGE_SIZE,
    FRAME_CAN,
    FRAME_CONTROL,
    HEADER,
    TCP_FRAME_SIZE,
    TCP_MARKER,
)
from analyzer.protocol.types import CRC_MISMATCH, GARBAGE, INCOMPLETE, Event, diagnostic

# Frame type byte -> bytes up to and including the CRC.
FRAME_LENGTHS: dict[int, int] = {
    FRAME_CONTROL: TCP_FRAME_SIZE,
    FRAME_CAN: TCP_FRAME_SIZE,
    **FRAME_SIZES,
}
GARBAGE_REPORT_LIMIT = 4096  # report a long run of garbage in pieces of at most this size
RAW_PREVIEW = 64  # bytes of a garbage run kept in its diagnostic


@dataclass(frozen=True, slots=True)
class RawFrame:
    """A frame cut from the stream whose CRC checked (or was legitimately not set)."""

    time: float
    frame_type: int
    data: bytes
    crc_set: bool = True


def wrap_control(can_data: bytes) -> bytes:
    """8 CAN data bytes of a command -> a 24-byte TCP/UART control frame (type 0x0A)."""
    if len(can_data) != 8:
        raise ValueError(f"control frames carry 8 CAN data bytes, got {len(can_data)}")
    body = HEADER + bytes([FRAME_CONTROL]) + bytes(9) + TCP_MARKER + bytes(can_data)
    return body + crc_bytes(body)


def wrap_can(can_id: int, data: bytes, *, with_crc: bool = False) -> bytes:
    """A CAN frame -> a 24-byte type-0x0B frame; the CRC is ``00 00`` unless asked for."""
    if len(data) > 8:
        raise ValueError(f"a CAN frame carries at most 8 data bytes, got {len(data)}")
    body = (
        HEADER
        + bytes([FRAME_CAN])
        + can_id.to_bytes(4, "big")
        + bytes(5)
        + TCP_MARKER
        + bytes(data).ljust(8, b"\0")
    )
    return body + (crc_bytes(body) if with_crc else b"\0\0")


class StreamFramer:
    """Cuts frames out of a byte stream that may split, glue or garble them.

    Sans-IO: ``feed(bytes, time)`` returns RawFrames and diagnostics. Every byte fed ends
    up either in a frame (``bytes_framed``, trailing zero padding of feedback frames
    included) or in a diagnostic (``bytes_discarded``); ``pending`` bytes wait for more.
    """

    def __init__(self, source: str, direction: str = "") -> None:
        self.source = source
        self.direction = direction
        self.bytes_fed = 0
        self.bytes_framed = 0
        self.bytes_discarded = 0
        self._buf = bytearray()
        self._garbage = bytearray()
        self._garbage_count = 0
        self._garbage_time = 0.0
        self._pad = 0  # zero bytes that may still follow the last feedback frame

    @property
    def pending(self) -> int:
        return len(self._buf) + self._garbage_count

    def feed(self, data: bytes, time: float) -> list[RawFrame | Event]:
        self.bytes_fed += len(data)
        self._buf += data
        return self._drain(time, final=False)

    def close(self, time: float) -> list[RawFrame | Event]:
        """End of stream: whatever is left is reported."""
        out = self._drain(time, final=True)
        self._flush_garbage(out)
        return out

    def tick(self, now: float) -> list[RawFrame | Event]:
        """Live use: report skipped bytes now instead of at the next frame."""
        out: list[RawFrame | Event] = []
        self._flush_garbage(out)
        return out

    # -- internals ---------------------------------------------------------------------------

    def _diag(self, time: float, kind: str, detail: str, raw: bytes) -> Event:
        self.bytes_discarded += len(raw)
        extra = {"direction": self.direction} if self.direction else {}
        return diagnostic(time, self.source, kind, detail, raw, **extra)

    def _to_garbage(self, n: int, time: float, out: list[RawFrame | Event]) -> None:
        if not n:
            return
        if not self._garbage_count:
            self._garbage_time = time
        room = RAW_PREVIEW - len(self._garbage)
        if room > 0:
            self._garbage += self._buf[: min(n, room)]
        self._garbage_count += n
        del self._buf[:n]
        if self._garbage_count >= GARBAGE_REPORT_LIMIT:
            self._flush_garbage(out)

    def _flush_garbage(self, out: list[RawFrame | Event]) -> None:
        if not self._garbage_count:
            return
        count = self._garbage_count
        shown = bytes(self._garbage)
        more = "" if count <= len(shown) else f" (first {len(shown)} shown)"
        event = diagnostic(
            self._garbage_time,
            self.source,
            GARBAGE,
            f"{count} byte(s) outside any frame skipped{more}",
            shown,
            **({"direction": self.direction} if self.direction else {}),
        )
        event.fields["byte_count"] = count
        self.bytes_discarded += count
        out.append(event)
        self._garbage.clear()
        self._garbage_count = 0

    def _drain(self, time: float, final: bool) -> list[RawFrame | Event]:
        out: list[RawFrame | Event] = []
        buf = self._buf
        while buf:
            if self._pad:
                self._skip_padding(buf)
                if not buf:
                    break
            start = buf.find(HEADER)
            if start < 0:
                keep = 1 if (buf[-1] == HEADER[0] and not final) else 0
                self._to_garbage(len(buf) - keep, time, out)
                break
            self._to_garbage(start, time, out)
            if len(buf) < 3:
                if final:
                    self._ended_inside(time, "stream ended inside a frame header", out)
                break
            frame_type = buf[2]
            size = FRAME_LENGTHS.get(frame_type)
            if size is None:
                # EB 90 followed by an unknown type: not a frame start.
                self._to_garbage(2, time, out)
                continue
            if len(buf) < size:
                if final:
                    self._ended_inside(
                        time,
                        f"stream ended after {len(buf)} of {size} bytes of a type "
                        f"0x{frame_type:02X} frame",
                        out,
                    )
                break
            frame = bytes(buf[:size])
            verdict = self._verdict(frame)
            self._flush_garbage(out)
            if verdict is None:
                self._rejected(time, frame, size, out)
                continue
            out.append(RawFrame(time, frame_type, frame, crc_set=verdict))
            del buf[:size]
            self.bytes_framed += size
            if size < FEEDBACK_MESSAGE_SIZE and frame_type not in (FRAME_CONTROL, FRAME_CAN):
                self._pad = FEEDBACK_MESSAGE_SIZE - size
        return out

    def _skip_padding(self, buf: bytearray) -> None:
        """The zeros that pad a short feedback frame to FEEDBACK_MESSAGE_SIZE: framed."""
        n = 0
        limit = min(self._pad, len(buf))
        while n < limit and buf[n] == 0:
            n += 1
        del buf[:n]
        self.bytes_framed += n
        self._pad = 0 if n < limit else self._pad - n

    def _ended_inside(self, time: float, detail: str, out: list[RawFrame | Event]) -> None:
        """The stream ended inside a frame: what is left is an incomplete frame."""
        buf = self._buf
        self._flush_garbage(out)
        out.append(self._diag(time, INCOMPLETE, detail, bytes(buf)))
        buf.clear()

    def _rejected(self, time: float, frame: bytes, size: int, out: list[RawFrame | Event]) -> None:
        """A frame whose CRC fails: cut short by a new header (those bytes lost), or
        damaged (with its padding); either way a diagnostic, and the bytes go."""
        buf = self._buf
        frame_type = frame[2]
        restart = frame.find(HEADER, 1)
        if restart > 0:
            out.append(
                self._diag(
                    time,
                    INCOMPLETE,
                    f"type 0x{frame_type:02X} frame cut short after {restart} of {size} bytes "
                    "(a new header follows; bytes lost?)",
                    frame[:restart],
                )
            )
            del buf[:restart]
            return
        if frame_type in FRAME_SIZES:
            # The zero padding of a damaged feedback frame belongs to it, as for a good one.
            while size < min(len(buf), FEEDBACK_MESSAGE_SIZE) and buf[size] == 0:
                size += 1
        out.append(self._diag(time, CRC_MISMATCH, _crc_detail(frame), bytes(buf[:size])))
        del buf[:size]

    @staticmethod
    def _verdict(frame: bytes) -> bool | None:
        """True: CRC checks; False: CRC legitimately not set; None: reject."""
        if check_crc(frame):
            return True
        if frame[2] == FRAME_CAN and frame[-2:] == b"\0\0" and frame[12:14] == TCP_MARKER:
            return False
        return None


def _crc_detail(frame: bytes) -> str:
    got = int.from_bytes(frame[-2:], "little")
    want = crc16(frame[:-2])
    detail = (
        f"type 0x{frame[2]:02X} frame: CRC {got & 0xFF:02X} {got >> 8:02X} on the wire, "
        f"{want & 0xFF:02X} {want >> 8:02X} computed"
    )
    if frame[2] in (FRAME_CONTROL, FRAME_CAN) and frame[12:14] != TCP_MARKER:
        where = frame.find(TCP_MARKER, 3)
        if where > 12:
            extra = where - 12
            detail += (
                f"; marker 40 88 at offset {where} instead of 12: {extra} byte(s) too many "
                "before it (bad frame length)"
            )
        else:
            detail += "; marker 40 88 missing at offset 12"
    return detail
