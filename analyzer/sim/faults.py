"""Fault injection on feedback segments: drop, corrupt, duplicate, delay, and feedback outages."""

from __future__ import annotations

import random
from collections import Counter
from dataclasses import dataclass

from analyzer.protocol.feedback import FRAME_SIZES, segments

DELAY_S = 0.3  # a delayed segment comes this late (the decoder warns above 0.2 s)
FAULT_KINDS = ("drop", "corrupt", "duplicate", "delay")


@dataclass(frozen=True)
class FaultConfig:
    """Rates (0..1, per segment) and the feedback outage window (seconds after the start)."""

    drop: float = 0.0
    corrupt: float = 0.0
    duplicate: float = 0.0
    delay: float = 0.0
    delay_s: float = DELAY_S
    stop_at: float | None = None
    stop_for: float = 0.0
    seed: int | None = None

    def __post_init__(self) -> None:
        for kind in FAULT_KINDS:
            rate = getattr(self, kind)
            if not 0.0 <= rate <= 1.0:
                raise ValueError(f"--{kind} {rate}: a rate must be between 0 and 1")
        if self.stop_for < 0 or self.delay_s < 0:
            raise ValueError("durations must not be negative")

    @property
    def active(self) -> bool:
        return any(getattr(self, k) for k in FAULT_KINDS) or self.stop_at is not None

    def describe(self) -> str:
        parts = [f"{k} {getattr(self, k) * 100:g}%" for k in FAULT_KINDS if getattr(self, k)]
        if self.stop_at is not None:
            parts.append(f"no feedback from {self.stop_at:g} s for {self.stop_for:g} s")
        if not parts:
            return "none"
        return ", ".join(parts) + (f" (seed {self.seed})" if self.seed is not None else "")


class FaultInjector:
    """Applies a FaultConfig to feedback messages with a seeded random generator.

    Corruption flips bits only in bytes the CRC covers (or the CRC itself), never in the
    EB 90 header or the length byte, so a corrupted message is reported as a CRC mismatch
    rather than as a missing header. A delayed segment also delays those after it, as a
    CAN controller sends its queue in order.
    """

    def __init__(self, config: FaultConfig) -> None:
        self.config = config
        self.rng = random.Random(config.seed)
        self.counts: Counter[str] = Counter()

    def feedback_stopped(self, elapsed: float) -> bool:
        """True while the configured outage lasts (``elapsed`` = seconds since the start)."""
        start = self.config.stop_at
        return start is not None and start <= elapsed < start + self.config.stop_for

    def segments(self, message: bytes) -> list[tuple[float, bytes]]:
        """A 32-byte feedback message -> (delay in seconds, segment) in sending order."""
        cfg, rng = self.config, self.rng
        size = FRAME_SIZES.get(message[2], len(message)) if len(message) > 2 else len(message)
        out: list[tuple[float, bytes]] = []
        delay = 0.0
        for index, segment in enumerate(segments(message)):
            # Draw every number every time, so one rate does not shift another's pattern.
            drop, corrupt, late, twice = (rng.random() for _ in range(4))
            if drop < cfg.drop:
                self.counts["drop"] += 1
                continue
            if corrupt < cfg.corrupt:
                segment = self._corrupt(segment, index * len(segment), size)
            if late < cfg.delay:
                self.counts["delay"] += 1
                delay += cfg.delay_s
            out.append((delay, segment))
            if twice < cfg.duplicate:
                self.counts["duplicate"] += 1
                out.append((delay, segment))
        return out

    def _corrupt(self, segment: bytes, start: int, checked_size: int) -> bytes:
        """Flip bits in one byte of message offsets 3 .. checked_size-1 within this segment."""
        lo = max(start, 3) - start
        hi = min(start + len(segment), checked_size) - start
        if lo >= hi:
            return segment
        self.counts["corrupt"] += 1
        data = bytearray(segment)
        data[self.rng.randrange(lo, hi)] ^= self.rng.randrange(1, 256)
        return bytes(data)
