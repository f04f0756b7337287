"""Feedback health over time: messages per second, silences that lost messages, CRC errors."""

from __future__ import annotations

import math
from typing import Any

from analyzer.analysis.findings import (
    CHECK_FEEDBACK,
    CHECK_FEEDBACK_GAP,
    DEGRADED,
    FEEDBACK_COMMAND,
    HEALTHY,
    LOST,
    UNKNOWN,
    ResponseFinding,
)
from analyzer.feedback_track import EXPECTED_FEEDBACK_HZ as EXPECTED_HZ
from analyzer.feedback_track import FEEDBACK_PERIOD_S, FeedbackClock, Silence
from analyzer.feedback_track import FEEDBACK_TOLERANCE as RATE_TOLERANCE

WINDOW_S = 60.0
# Times are compared with this much room, as (t - first) // WINDOW_S rounds.
WINDOW_MARGIN_S = 1e-3
MIN_LAST_WINDOW_S = 5.0  # a shorter last window is folded into the judgement only if it has data


class FeedbackHealth:
    """Folds feedback times and feedback errors; findings per silence and per minute.

    Silences are timed per stream (source and direction) by a ``FeedbackClock``, the
    tally's clock: its gaps are the summary's gaps."""

    def __init__(self) -> None:
        self.first: float | None = None  # first event of the input, feedback or not
        self.last: float | None = None
        self.last_feedback: float | None = None
        self.clock = FeedbackClock()  # when each stream's feedback last came
        self._window = 0
        self._next_window = -math.inf  # no time before this closes a window
        self._window_messages = 0
        self._window_gaps = 0
        self._window_lost = 0
        self._window_errors = 0
        self.messages = 0
        self.gaps = 0
        self.lost = 0

    def tick(self, t: float) -> list[ResponseFinding]:
        """Any event's time: closes the minute windows that ended before ``t``."""
        if t < self._next_window:  # the most frequent: nothing closes (``first`` is set)
            if t > self.last:  # type: ignore[operator]
                self.last = t
            return []
        first = self.first
        if first is None:
            first = self.first = t
        if self.last is None or t > self.last:
            self.last = t
        window = int((t - first) // WINDOW_S)  # the minute window of ``t``
        if window > self._window:
            # One judgement for the window that ended; empty windows in between (a long
            # silence, or a clock that jumps by years) are not listed one by one.
            found = [self._judge_window(WINDOW_S)]
            self._window = window
            self._next_window = first + (window + 1) * WINDOW_S - WINDOW_MARGIN_S
            return found
        self._next_window = first + (self._window + 1) * WINDOW_S - WINDOW_MARGIN_S
        return []

    def feedback(self, t: float, stream: str = "") -> list[ResponseFinding]:
        """One feedback message at ``t`` of ``stream``; a finding when it ends a silence
        that lost messages."""
        out = self.tick(t)
        self.messages += 1
        self._window_messages += 1
        self.last_feedback = t
        arrivals = self.clock.messages(stream, [t])
        if arrivals is None:  # as the tally: streams beyond so many are counted, not timed
            return out
        for silence in arrivals:
            out += self._ended(silence)
        return out

    def error(
        self, t: float, stream: str = "", *, ends_silence: bool = True
    ) -> list[ResponseFinding]:
        """A damaged feedback message (CRC error, incomplete) at ``t`` of ``stream``,
        counted as damaged. A message with a bad CRC came whole: the silence before it
        ends there, so it is not also lost (``ends_silence``; as the tally times it)."""
        out = self.tick(t)
        self._window_errors += 1
        silence = self.clock.damaged(stream, t) if ends_silence else None
        return out if silence is None else out + self._ended(silence)

    def _ended(self, silence: Silence) -> list[ResponseFinding]:
        """A message (whole or damaged) ended ``silence``: a finding if it lost messages."""
        out: list[ResponseFinding] = []
        previous, t = silence.start, silence.end
        gap = t - previous
        lost = silence.lost
        if lost:
            self.gaps += 1
            self.lost += lost
            self._window_gaps += 1
            self._window_lost += lost
            words = f"{lost} message{'s' if lost > 1 else ''}"
            text = (
                f"feedback lost: {words} missing, no feedback for {gap:.1f} s "
                f"(expected every {FEEDBACK_PERIOD_S:g} s)"
            )
            extra = {"gap_s": gap, "lost_messages": lost, "observed_at": t}
            out.append(
                ResponseFinding(FEEDBACK_COMMAND, previous, CHECK_FEEDBACK_GAP, LOST, text, extra)
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

    def close(self) -> list[ResponseFinding]:
        if self.first is None or self.last is None:
            return []
        length = self.last - (self.first + self._window * WINDOW_S)
        if self._window > 0 and length < MIN_LAST_WINDOW_S and not self._window_messages:
            return []
        return [self._judge_window(max(length, 0.0))]

    def _judge_window(self, length: float) -> ResponseFinding:
        assert self.first is not None
        start = self.first + self._window * WINDOW_S
        messages, gaps, errors = self._window_messages, self._window_gaps, self._window_errors
        lost = self._window_lost
        self._window_messages = self._window_gaps = self._window_errors = self._window_lost = 0
        extra: dict[str, Any] = {
            "gaps": gaps,
            "lost_messages": lost,
            "crc_errors": errors,
            "window_s": length,
        }
        if not messages:
            verdict = UNKNOWN if self.messages == 0 else LOST
            what = "no gimbal feedback in the input" if not self.messages else "no feedback"
            text = f"{what} for {length:.0f} s: the responses cannot be judged"
            return ResponseFinding(FEEDBACK_COMMAND, start, CHECK_FEEDBACK, verdict, text, extra)
        hz = messages / length if length >= 1.0 else None
        extra["feedback_hz"] = hz
        problems = []
        if hz is not None and abs(hz - EXPECTED_HZ) > RATE_TOLERANCE * EXPECTED_HZ:
            problems.append(f"{hz:.2f} messages/s instead of {EXPECTED_HZ:g}")
        if gaps:
            problems.append(
                f"{gaps} gap{'s' if gaps > 1 else ''} ({lost} message{'s' if lost > 1 else ''} "
                "lost)"
            )
        if errors:
            problems.append(f"{errors} damaged message{'s' if errors > 1 else ''} (CRC/incomplete)")
        rate = f"{hz:.2f} messages/s" if hz is not None else f"{messages} messages"
        if problems:
            text = f"feedback over {length:.0f} s: " + ", ".join(problems)
            return ResponseFinding(FEEDBACK_COMMAND, start, CHECK_FEEDBACK, DEGRADED, text, extra)
        text = f"feedback healthy over {length:.0f} s: {rate}, no message lost, no CRC error"
        return ResponseFinding(FEEDBACK_COMMAND, start, CHECK_FEEDBACK, HEALTHY, text, extra)
