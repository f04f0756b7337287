"""Feedback health over time: messages per second, silences, CRC errors per minute."""

from __future__ import annotations

import math
from collections import Counter
from typing import Any

from analyzer.analysis.findings import (
    CHECK_FEEDBACK,
    CHECK_FEEDBACK_GAP,
    FEEDBACK_COMMAND,
    NOT_OBEYED,
    OBEYED,
    PARTIAL,
    UNKNOWN,
    Finding,
)
from analyzer.tally import EXPECTED_FEEDBACK_HZ as EXPECTED_HZ
from analyzer.tally import FEEDBACK_TOLERANCE as RATE_TOLERANCE
from analyzer.tally import GAP_THRESHOLD_S

WINDOW_S = 60.0
MIN_LAST_WINDOW_S = 5.0  # a shorter last window is folded into the judgement only if it has data


class FeedbackHealth:
    """Folds feedback times and feedback errors; findings per silence and per minute."""

    def __init__(self) -> None:
        self.per_second: Counter[int] = Counter()  # whole Unix second -> feedback messages
        self.errors_per_minute: Counter[int] = Counter()  # window index -> CRC / incomplete
        self.gaps: list[tuple[float, float]] = []  # (last message before, first message after)
        self.first: float | None = None  # first event of the input, feedback or not
        self.last: float | None = None
        self.last_feedback: float | None = None
        self._window = 0
        self._window_messages = 0
        self._window_gaps = 0
        self._window_errors = 0
        self.messages = 0

    def _window_of(self, t: float) -> int:
        assert self.first is not None
        return int((t - self.first) // WINDOW_S)

    def tick(self, t: float) -> list[Finding]:
        """Any event's time: closes the minute windows that ended before ``t``."""
        if self.first is None:
            self.first = t
        if self.last is None or t > self.last:
            self.last = t
        out: list[Finding] = []
        window = self._window_of(t)
        if window > self._window:
            # One judgement for the window that ended; empty windows in between (a long
            # silence, or a clock that jumps by years) are not listed one by one.
            out.append(self._judge_window(WINDOW_S))
            self._window = window
        return out

    def feedback(self, t: float) -> list[Finding]:
        out = self.tick(t)
        self.per_second[math.floor(t)] += 1
        self.messages += 1
        self._window_messages += 1
        previous, self.last_feedback = self.last_feedback, t
        if previous is not None and t - previous > GAP_THRESHOLD_S:
            self.gaps.append((previous, t))
            self._window_gaps += 1
            gap = t - previous
            out.append(
                Finding(
                    FEEDBACK_COMMAND,
                    previous,
                    CHECK_FEEDBACK_GAP,
                    NOT_OBEYED,
                    f"no feedback for {gap:.1f} s (expected every {1 / EXPECTED_HZ:.1f} s)",
                    {"gap_s": gap, "observed_at": t},
                )
            )
        return out

    def open_since(self) -> list[float]:
        """The times findings still to come of the feedback can carry: the open window's
        start, the last feedback message (a silence after it is named from it)."""
        if self.first is None:
            return []
        times = [self.first + self._window * WINDOW_S]
        if self.last_feedback is not None:
            times.append(self.last_feedback)
        return times

    def error(self, t: float) -> list[Finding]:
        out = self.tick(t)
        self.errors_per_minute[self._window_of(t)] += 1
        self._window_errors += 1
        return out

    def close(self) -> list[Finding]:
        if self.first is None or self.last is None:
            return []
        length = self.last - (self.first + self._window * WINDOW_S)
        if self._window > 0 and length < MIN_LAST_WINDOW_S and not self._window_messages:
            return []
        return [self._judge_window(max(length, 0.0))]

    def _judge_window(self, length: float) -> Finding:
        assert self.first is not None
        start = self.first + self._window * WINDOW_S
        messages, gaps, errors = self._window_messages, self._window_gaps, self._window_errors
        self._window_messages = self._window_gaps = self._window_errors = 0
        extra: dict[str, Any] = {"gaps": gaps, "crc_errors": errors, "window_s": length}
        if not messages:
            verdict = UNKNOWN if self.messages == 0 else NOT_OBEYED
            what = "no gimbal feedback in the input" if not self.messages else "no feedback"
            text = f"{what} for {length:.0f} s: the responses cannot be judged"
            return Finding(FEEDBACK_COMMAND, start, CHECK_FEEDBACK, verdict, text, extra)
        hz = messages / length if length >= 1.0 else None
        extra["feedback_hz"] = hz
        problems = []
        if hz is not None and abs(hz - EXPECTED_HZ) > RATE_TOLERANCE * EXPECTED_HZ:
            problems.append(f"{hz:.2f} messages/s instead of {EXPECTED_HZ:g}")
        if gaps:
            problems.append(f"{gaps} silence{'s' if gaps > 1 else ''} over {GAP_THRESHOLD_S:g} s")
        if errors:
            problems.append(f"{errors} damaged message{'s' if errors > 1 else ''} (CRC/incomplete)")
        rate = f"{hz:.2f} messages/s" if hz is not None else f"{messages} messages"
        if problems:
            text = f"feedback over {length:.0f} s: " + ", ".join(problems)
            return Finding(FEEDBACK_COMMAND, start, CHECK_FEEDBACK, PARTIAL, text, extra)
        text = f"feedback healthy over {length:.0f} s: {rate}, no silence, no CRC error"
        return Finding(FEEDBACK_COMMAND, start, CHECK_FEEDBACK, OBEYED, text, extra)
