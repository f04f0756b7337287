"""TCP reassembly of one direction of a connection: segments in any order -> bytes in order."""

from __future__ import annotations

import heapq
from dataclasses import dataclass

SEQ_MOD = 1 << 32
HALF = 1 << 31
MAX_PENDING_BYTES = 1 << 20  # out-of-order data held while waiting for a missing segment
MAX_PENDING_SEGMENTS = 4096  # segments held: many tiny ones must not cost more than their bytes
MAX_WAIT_S = 10.0  # capture seconds to wait for a missing segment before giving up on it
WINDOW = 1 << 26  # data further ahead than this is not part of this connection


@dataclass(frozen=True, slots=True)
class Delivered:
    """Stream bytes now in order; ``offset`` counts from the connection's first byte."""

    time: float
    offset: int
    data: bytes


@dataclass(frozen=True, slots=True)
class Gap:
    """Bytes the capture never saw (a lost segment): the stream goes on after them."""

    time: float
    offset: int
    size: int


Result = Delivered | Gap


class TcpDirection:
    """Sans-IO reassembler for one direction of one TCP connection.

    ``segment(seq, payload, time)`` takes segments as captured: out of order, repeated
    (retransmissions) or overlapping each other. Bytes come out once, in order; where two
    segments disagree about the same bytes the first one delivered wins. A hole that is
    not filled within ``max_wait`` capture seconds, or while more than ``max_pending``
    bytes wait behind it, is given up as a ``Gap``; ``flush`` does the same at the end.

    Accounting: ``bytes_in == bytes_delivered + bytes_duplicate + bytes_out_of_window +
    bytes_pending`` at all times; ``bytes_missing`` counts the bytes of the gaps.
    """

    def __init__(
        self, *, max_pending: int = MAX_PENDING_BYTES, max_wait: float = MAX_WAIT_S
    ) -> None:
        self.max_pending = max_pending
        self.max_wait = max_wait
        self.base: int | None = None  # sequence number of stream offset 0
        self.from_syn = False  # the base is the SYN's: no byte of the stream lies before it
        self.next = 0  # offset of the next byte to deliver
        self.fin_seen = False
        self._pending: dict[int, tuple[bytes, float]] = {}  # offset -> (data, time seen)
        self._starts: list[int] = []  # heap of the offsets in _pending
        self.bytes_in = 0
        self.bytes_delivered = 0
        self.bytes_duplicate = 0  # retransmitted / overlapping / older than the first segment
        self.bytes_out_of_window = 0
        self.bytes_pending = 0
        self.bytes_missing = 0
        self.gaps = 0

    def syn(self, seq: int) -> None:
        """A SYN: the stream starts right after ``seq``."""
        if self.base is None:
            self.base = (seq + 1) % SEQ_MOD
            self.from_syn = True

    def _offset(self, seq: int) -> int:
        assert self.base is not None
        expected = (self.base + self.next) % SEQ_MOD
        delta = (seq - expected + HALF) % SEQ_MOD - HALF
        return self.next + delta

    def segment(self, seq: int, data: bytes, time: float, *, syn: bool = False) -> list[Result]:
        """One captured segment (its sequence number and payload)."""
        seq %= SEQ_MOD
        if syn:
            self.syn(seq)
            seq = (seq + 1) % SEQ_MOD
        if self.base is None:
            self.base = seq  # capture started in the middle of the connection
        if not data:
            return []
        out: list[Result] = []
        size = len(data)
        self.bytes_in += size
        start = self._offset(seq)
        end = start + size
        if start < 0 and self.from_syn:  # before the SYN: no byte of this stream is
            self.bytes_out_of_window += size  # (a damaged SYN or sequence number)
        elif end <= self.next:
            self.bytes_duplicate += size
        elif start - self.next > WINDOW:
            self.bytes_out_of_window += size
        elif start > self.next:
            self._hold(start, data, time)
        else:
            self._deliver(start, data, time, out)
            self._drain(time, out)
        if self._pending:
            self._give_up_stale(time, out)
        return out

    def flush(self, time: float) -> list[Result]:
        """End of the capture (or a reset): deliver everything held, reporting the holes."""
        out: list[Result] = []
        while self._pending:
            self._skip_to_first(time, out)
            self._drain(time, out)
        return out

    # -- internals -------------------------------------------------------------------------

    def _hold(self, start: int, data: bytes, time: float) -> None:
        held = self._pending.get(start)
        if held is not None:
            if len(held[0]) >= len(data):
                self.bytes_duplicate += len(data)
                return
            self.bytes_duplicate += len(held[0])
            self.bytes_pending -= len(held[0])
        else:
            heapq.heappush(self._starts, start)
        self._pending[start] = (data, time)
        self.bytes_pending += len(data)

    def _deliver(self, start: int, data: bytes, time: float, out: list[Result]) -> None:
        """``start <= next``: hand on the part of ``data`` not delivered yet."""
        skip = self.next - start
        if skip >= len(data):
            self.bytes_duplicate += len(data)
            return
        self.bytes_duplicate += skip
        fresh = data[skip:] if skip else data
        out.append(Delivered(time, self.next, fresh))
        self.next += len(fresh)
        self.bytes_delivered += len(fresh)

    def _drain(self, time: float, out: list[Result]) -> None:
        starts = self._starts
        while starts and starts[0] <= self.next:
            start = heapq.heappop(starts)
            data, _seen = self._pending.pop(start)
            self.bytes_pending -= len(data)
            self._deliver(start, data, time, out)

    def _skip_to_first(self, time: float, out: list[Result]) -> None:
        first = self._starts[0]
        if first > self.next:
            size = first - self.next
            out.append(Gap(time, self.next, size))
            self.bytes_missing += size
            self.gaps += 1
            self.next = first

    def _give_up_stale(self, time: float, out: list[Result]) -> None:
        while self._pending and (
            self.bytes_pending > self.max_pending
            or len(self._pending) > MAX_PENDING_SEGMENTS
            or time - self._pending[self._starts[0]][1] > self.max_wait
        ):
            self._skip_to_first(time, out)
            self._drain(time, out)
