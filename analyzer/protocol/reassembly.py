"""Reassembly of 32-byte gimbal feedback messages from their four 8-byte CAN segments."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, NamedTuple

from analyzer.protocol.crc import crc16
from analyzer.protocol.feedback import FRAME_SIZES, decode_feedback
from analyzer.protocol.ids import HEADER
from analyzer.protocol.types import CRC_MISMATCH, DUPLICATE, INCOMPLETE, Event, diagnostic

# The warning of a feedback message whose segments came far apart: its time (the last
# segment's) is later than when the gimbal measured what it says.
LATE_SEGMENT = "late segment"

SEGMENTS_PER_MESSAGE = 4
LATE_AFTER_S = 0.2  # a gap between segments of one message worth a warning


class Segment(NamedTuple):
    """One 8-byte CAN segment and its time (a tuple: the usual case makes it cheaply)."""

    time: float
    data: bytes


# ``Segment((time, data))`` without the named tuple's Python-level constructor.
_segment = functools.partial(tuple.__new__, Segment)


@dataclass(slots=True)
class Message:
    """A reassembled message whose CRC checked."""

    time: float  # time of the segment that completed it
    data: bytes
    segments: tuple[Segment, ...]
    warnings: tuple[str, ...] = ()


def _is_header(data: bytes) -> bool:
    return len(data) >= 3 and data[:2] == HEADER and data[2] in FRAME_SIZES


def _crc_ok(data: bytes) -> bool:
    """Whether ``data`` is a feedback message (by its length byte) whose CRC checks."""
    size = FRAME_SIZES.get(data[2]) if len(data) >= 3 else None
    if size is None or len(data) < size:
        return False
    return crc16(data[: size - 2]) == data[size - 2] | data[size - 1] << 8


class FeedbackReassembler:
    """Turns the segment stream of CAN ID 0x030F0001 into messages and diagnostics.

    A segment starting with EB 90 only starts a message when the CRC confirms it, so a
    payload that happens to hold EB 90 is no false start. Missing segments, repeated
    segments, corrupted messages and late segments are reported; every byte fed is in a
    message (``bytes_framed``) or a diagnostic (``bytes_discarded``) once resolved.
    """

    def __init__(
        self,
        source: str,
        *,
        late_after: float = LATE_AFTER_S,
        stale_after: float = 1.0,
        fast: bool = True,
    ) -> None:
        self.source = source
        self.late_after = late_after  # gap between segments of one message worth a warning
        self.stale_after = stale_after  # a partial message older than this is given up
        self.bytes_fed = 0
        self.bytes_framed = 0
        self.bytes_discarded = 0
        self._pending: list[Segment] = []
        # The last segment of the last message, to spot its repeat. Only right after that
        # message: a lone equal segment 500 ms later is what is left of the next message
        # (a gimbal at rest sends the same message again and again).
        self._last_tail = b""
        self._last_tail_time = 0.0
        # The usual case, a header and the three segments after it, takes a short way
        # (same results): ``_open`` says that 1-3 segments are pending, the first a
        # header that repeats nothing. ``fast=False`` always takes the long way (tests).
        self._fast = fast
        self._open = False

    @property
    def pending(self) -> int:
        return sum(len(s.data) for s in self._pending)

    def feed(self, data: bytes, time: float) -> list[Message | Event]:
        self.bytes_fed += len(data)
        pending = self._pending
        if self._open:  # the short way: a header is pending (never set when not fast)
            if time - pending[-1][0] <= self.stale_after:
                if len(pending) < SEGMENTS_PER_MESSAGE - 1:
                    pending.append(_segment((time, bytes(data))))
                    return []
                message = pending[0][1] + pending[1][1] + pending[2][1] + data
                if _crc_ok(message):
                    segs = [*pending, _segment((time, bytes(data)))]
                    pending.clear()
                    self._open = False
                    out: list[Message | Event] = []
                    self._emit(out, segs, data=message)
                    return out
        elif self._fast and not pending and _is_header(data) and not self._repeats_tail(data, time):
            pending.append(_segment((time, bytes(data))))
            self._open = True
            return []
        out = []
        if pending and time - pending[-1].time > self.stale_after:
            self._resolve(out, final=True, time=time)
        pending.append(Segment(time, bytes(data)))
        self._resolve(out, final=False, time=time)
        return out

    def feed_segments(
        self,
        times: list[float],
        blob: bytes,
        sizes: list[int],
        whole: list[bool],
        regular: int = 0,
    ) -> tuple[list[int], list[tuple[int, list[Message | Event]]]]:
        """Segments in a row, as ``feed`` takes them one by one: segment ``j`` is
        ``blob[8 * j : 8 * j + sizes[j]]`` at ``times[j]``.

        ``whole[j]`` says that segments ``j`` to ``j + 3`` are a message with nothing to
        remark (8 bytes each, a header first, the CRC right, no segment late): it is taken
        whole when nothing is pending and it repeats no segment. ``regular``: the first
        that many messages are such messages, one after the other, none starting with the
        segment that ends the one before (taken at once). Returns where the messages taken
        whole start (the caller decodes them), and what ``feed`` gave for the other
        segments, by index."""
        taken: list[int] = []
        fed: list[tuple[int, list[Message | Event]]] = []
        size = 8 * SEGMENTS_PER_MESSAGE
        j, n = 0, len(times)
        if regular and not self._pending and not self._repeats_tail(blob[:8], times[0]):
            j = regular * SEGMENTS_PER_MESSAGE
            taken = list(range(0, j, SEGMENTS_PER_MESSAGE))
            self.bytes_fed += regular * size
            self.bytes_framed += regular * size
            self._last_tail = blob[8 * j - 8 : 8 * j]
            self._last_tail_time = times[j - 1]
        while j < n:
            if whole[j] and not self._pending:
                start = 8 * j
                if not self._repeats_tail(blob[start : start + 8], times[j]):
                    end = j + SEGMENTS_PER_MESSAGE - 1
                    self.bytes_fed += size
                    self.bytes_framed += size
                    self._last_tail = blob[start + size - 8 : start + size]
                    self._last_tail_time = times[end]
                    taken.append(j)
                    j = end + 1
                    continue
            results = self.feed(blob[8 * j : 8 * j + sizes[j]], times[j])
            if results:
                fed.append((j, results))
            j += 1
        return taken, fed

    def _repeats_tail(self, data: bytes, time: float) -> bool:
        """Whether a segment repeats the last segment of the message just before it."""
        return (
            bool(self._last_tail)
            and data == self._last_tail
            and time - self._last_tail_time <= self.late_after
        )

    def tick(self, now: float) -> list[Message | Event]:
        out: list[Message | Event] = []
        if self._pending and now - self._pending[-1].time > self.stale_after:
            self._resolve(out, final=True, time=now)
        return out

    def close(self, time: float) -> list[Message | Event]:
        out: list[Message | Event] = []
        self._resolve(out, final=True, time=time)
        return out

    # -- internals ---------------------------------------------------------------------------

    def _report(
        self, out: list[Message | Event], kind: str, detail: str, segs: list[Segment], time: float
    ) -> None:
        raw = b"".join(s.data for s in segs)
        self.bytes_discarded += len(raw)
        out.append(diagnostic(time, self.source, kind, detail, raw, segments=len(segs)))

    def _emit(
        self,
        out: list[Message | Event],
        segs: list[Segment],
        extra: tuple[str, ...] = (),
        data: bytes | None = None,
    ) -> None:
        """A message of four segments whose CRC checked (``data``: their bytes, if known)."""
        if data is None:
            data = b"".join([s.data for s in segs])
        a, b, c, d = segs
        warnings = list(extra)
        gap = max(b.time - a.time, c.time - b.time, d.time - c.time)
        if gap > self.late_after:
            warnings.append(f"{LATE_SEGMENT}: {gap * 1000:.0f} ms between segments")
        if not len(a.data) == len(b.data) == len(c.data) == len(d.data) == 8:
            warnings.append(f"segment lengths {[len(s.data) for s in segs]}, expected 8 each")
        self.bytes_framed += len(data)
        self._last_tail = d.data
        self._last_tail_time = d.time
        out.append(Message(d.time, data, tuple(segs), tuple(warnings)))

    def _resolve(self, out: list[Message | Event], *, final: bool, time: float) -> None:
        self._settle(out, final=final, time=time)
        pending = self._pending
        self._open = (
            self._fast
            and 0 < len(pending) < SEGMENTS_PER_MESSAGE
            and _is_header(pending[0].data)
            and not self._repeats_tail(pending[0].data, pending[0].time)
        )

    def _settle(self, out: list[Message | Event], *, final: bool, time: float) -> None:
        pending = self._pending
        while pending:
            if self._repeats_tail(pending[0].data, pending[0].time):
                self._report(
                    out, DUPLICATE, "last feedback segment repeated", pending[:1], pending[0].time
                )
                del pending[:1]
                continue
            if not _is_header(pending[0].data):
                k = next((i for i, s in enumerate(pending) if _is_header(s.data)), len(pending))
                if k == len(pending) < SEGMENTS_PER_MESSAGE and not final:
                    break  # report a run of stray segments as one, once it ends
                self._report(
                    out,
                    INCOMPLETE,
                    f"{k} feedback segment(s) without a message header "
                    "(first segment lost or message cut)",
                    pending[:k],
                    time,
                )
                del pending[:k]
                continue
            if len(pending) < SEGMENTS_PER_MESSAGE:
                if final:
                    self._report(
                        out,
                        INCOMPLETE,
                        f"feedback message with only {len(pending)} of 4 segments",
                        pending[:],
                        time,
                    )
                    pending.clear()
                break
            first = pending[:SEGMENTS_PER_MESSAGE]
            if _crc_ok(b"".join(s.data for s in first)):
                self._emit(out, first)
                del pending[:SEGMENTS_PER_MESSAGE]
                continue
            # Segments that repeat the one before them: drop them and try again.
            candidate, repeated, used = [pending[0]], [], 1
            while len(candidate) < SEGMENTS_PER_MESSAGE and used < len(pending):
                segment = pending[used]
                if segment.data == candidate[-1].data:
                    repeated.append((len(candidate), segment))
                else:
                    candidate.append(segment)
                used += 1
            if repeated:
                if len(candidate) < SEGMENTS_PER_MESSAGE and not final:
                    break  # wait for more segments to tell a repeat from corruption
                if len(candidate) == SEGMENTS_PER_MESSAGE and _crc_ok(
                    b"".join(s.data for s in candidate)
                ):
                    for number, segment in repeated:
                        self._report(
                            out,
                            DUPLICATE,
                            f"feedback segment {number} repeated",
                            [segment],
                            segment.time,
                        )
                    notes = tuple(f"segment {number} was repeated" for number, _ in repeated)
                    self._emit(out, candidate, notes)
                    del pending[:used]
                    continue
            restart = next(
                (i for i in range(1, SEGMENTS_PER_MESSAGE) if _is_header(pending[i].data)), 0
            )
            if restart:
                self._report(
                    out,
                    INCOMPLETE,
                    f"feedback message with only {restart} of 4 segments before the "
                    "next header (segment lost?)",
                    pending[:restart],
                    time,
                )
                del pending[:restart]
                continue
            data = b"".join(s.data for s in first)
            self._report(out, CRC_MISMATCH, _crc_detail(data), first, first[-1].time)
            del pending[:SEGMENTS_PER_MESSAGE]


def _crc_detail(data: bytes) -> str:
    size = FRAME_SIZES[data[2]]
    if len(data) < size:
        return f"feedback message of {len(data)} bytes is too short for its CRC"
    got = data[size - 2 : size]
    want = crc16(data[: size - 2]).to_bytes(2, "little")
    return (
        f"feedback message type 0x{data[2]:02X}: CRC {got.hex(' ').upper()} on the wire, "
        f"{want.hex(' ').upper()} computed"
    )


def message_events(
    source: str,
    results: list[Message | Event],
    extra: dict[str, Any],
    warnings: list[str] | None = None,
) -> list[Event]:
    """What the reassembler gave, as events: each message decoded (``extra`` fields and
    the frame's ``warnings`` added), each diagnostic as it is (``extra`` added)."""
    out: list[Event] = []
    for result in results:
        if isinstance(result, Event):
            result.fields.update(extra)
            out.append(result)
            continue
        layout, fields, more = decode_feedback(result.data)
        assert layout is not None  # the reassembler only passes CRC-checked messages
        fields["raw"] = result.data.hex(" ").upper()
        if extra:
            fields.update(extra)
        if warnings or result.warnings:
            more = [*(warnings or []), *result.warnings, *more]
        out.append(Event(layout.topic, result.time, source, fields, more))
    return out
