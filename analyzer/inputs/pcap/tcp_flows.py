"""The TCP connections of a capture, bounded: how many are open and how much waits out of order."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from analyzer.inputs.pcap.tcp_reassembly import Gap, Result, TcpDirection

MAX_FLOWS = 4096  # connections reassembled at once; the least recently used one is closed
MAX_PENDING_TOTAL = 32 << 20  # out-of-order bytes held over all connections
COUNTERS = ("bytes_in", "bytes_delivered", "bytes_duplicate", "bytes_missing")
Key = tuple[tuple[str, int], tuple[str, int]]  # (client, server)


@dataclass
class Flow:
    """Both directions of one TCP connection with the IDU port."""

    source: str
    directions: dict[str, TcpDirection] = field(default_factory=dict)

    def direction(self, name: str) -> TcpDirection:
        state = self.directions.get(name)
        if state is None:
            state = self.directions[name] = TcpDirection()
        return state


@dataclass
class GivenUp:
    """What the bounds cost: connections closed early and the bytes lost by it."""

    flows: int = 0
    bytes: int = 0


# (flow, direction name, results) of one reassembly step
Output = list[tuple[Flow, str, list[Result]]]


class FlowTable:
    """Flows by (client, server), each reassembled per direction, within two bounds.

    More than ``max_flows`` open connections (a SYN flood, a port scan) close the least
    recently used one: what it holds is handed on with its holes reported. More than
    ``max_pending_total`` bytes waiting behind holes over all connections give up the
    holes of the least recently used connections first. ``given_up`` counts both.
    """

    def __init__(
        self, *, max_flows: int = MAX_FLOWS, max_pending_total: int = MAX_PENDING_TOTAL
    ) -> None:
        self.max_flows = max_flows
        self.max_pending_total = max_pending_total
        self._flows: dict[Key, Flow] = {}  # in order of last use
        self.opened = 0
        self.pending = 0
        self.given_up = GivenUp()
        self._closed = dict.fromkeys((*COUNTERS, "bytes_out_of_window"), 0)

    def segment(
        self,
        key: Key,
        name: str,
        direction: str,
        seq: int,
        payload: bytes,
        time: float,
        flags: int,
    ) -> Output:
        """One segment of connection ``key`` (``name`` names it when it is new)."""
        out: Output = []
        flow = self._flows.pop(key, None)
        if flow is None or (flags & 0x02 and _new_connection(flow, direction, seq)):
            if flow is not None:  # the same ports reused by a new connection
                out.extend(self._close(flow, time))
                generation = flow.source.rsplit("#", 1)
                number = int(generation[1]) + 1 if len(generation) == 2 else 2
                name = f"{name}#{number}"
            flow = Flow(name)
            self.opened += 1
            if len(self._flows) >= self.max_flows:
                oldest = next(iter(self._flows))
                self.given_up.flows += 1
                out.extend(self._close(self._flows.pop(oldest), time, given_up=True))
        self._flows[key] = flow  # now the most recently used
        state = flow.direction(direction)
        before = state.bytes_pending
        out.append((flow, direction, state.segment(seq, payload, time, syn=bool(flags & 0x02))))
        self.pending += state.bytes_pending - before
        if flags & 0x01:
            state.fin_seen = True
        if flags & 0x04:  # RST: nothing more will come, hand on what is held
            out.extend(self._flush(flow, time))
        if self.pending > self.max_pending_total:
            out.extend(self._relieve(time))
        return out

    def flush_all(self, time: float) -> Output:
        """The end of the capture: everything held is handed on, holes reported."""
        out: Output = []
        for flow in self._flows.values():
            out.extend(self._flush(flow, time))
        return out

    def totals(self) -> dict[str, int]:
        """Byte counters over all connections, closed ones included."""
        totals = dict(self._closed)
        for flow in self._flows.values():
            for state in flow.directions.values():
                for name in totals:
                    totals[name] += getattr(state, name)
        totals["flows"] = self.opened
        return totals

    def _flush(self, flow: Flow, time: float, given_up: bool = False) -> Output:
        out: Output = []
        for name, state in flow.directions.items():
            before = state.bytes_pending
            results = state.flush(time)
            self.pending -= before - state.bytes_pending
            if given_up:
                self.given_up.bytes += sum(r.size for r in results if isinstance(r, Gap))
            out.append((flow, name, results))
        return out

    def _close(self, flow: Flow, time: float, given_up: bool = False) -> Output:
        out = self._flush(flow, time, given_up)
        for state in flow.directions.values():
            for name in self._closed:
                self._closed[name] += getattr(state, name)
        return out

    def _relieve(self, time: float) -> Iterator[tuple[Flow, str, list[Result]]]:
        """Give up holes, least recently used connections first, until under the bound."""
        for flow in list(self._flows.values()):
            if self.pending <= self.max_pending_total // 2:
                return
            if any(s.bytes_pending for s in flow.directions.values()):
                yield from self._flush(flow, time, given_up=True)

    def __len__(self) -> int:
        return len(self._flows)


def _new_connection(flow: Flow, direction: str, seq: int) -> bool:
    """A SYN whose sequence number does not fit the connection seen so far."""
    state = flow.directions.get(direction)
    if state is None or state.base is None:
        return False
    return (seq + 1) % (1 << 32) != state.base
