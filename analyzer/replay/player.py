"""Plays a span of a flight to a gimbal: aligned first, every frame at its time, stopped by silence.

The player needs what the check's runner needs (``analyzer.check``): a link that sends
a frame and returns when it went (``CheckLink``, or the simulated bench), the attitude
feedback as it comes (the check's ``Observer``) and a clock (the wall clock, or the
simulated bench's virtual one). Before the first frame it brings the gimbal to the
attitude the flight began with (``analyzer.check.align.bring_to``). Each frame then goes
at its time in the flight, from the span's start, divided by the speed: the wait is
measured on the monotonic clock from one origin, so no error adds up over a long flight.
Between frames it looks at the feedback: a gimbal silent for SILENCE_S stops the replay.
Two link diagnostics mark the replayed span in the recording (``REPLAY``, ``REPLAY_END``):
``compare`` takes what lies between them as the replay, the alignment before it apart.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from analyzer.analysis.response import Settings
from analyzer.analysis.samples import MOTOR_YAW, PITCH, Sample
from analyzer.check.align import (
    WALL_CLOCK,
    Arrival,
    Clock,
    Goals,
    bring_to,
    centre,
    describe,
    time_needed,
)
from analyzer.check.judge import Limits
from analyzer.check.runner import AFTER_DEADLINE_S, FIRST_FEEDBACK_WAIT_S
from analyzer.protocol.types import Event
from analyzer.replay.flight import Span
from analyzer.sources.base import link_event

SILENCE_S = 3.0  # six feedback periods without a message: the gimbal is not answering
SLICE_S = 0.05  # between frames, the feedback is looked at this often
TICK_S = 1.0  # how often ``progress`` is called
REPLAY = "replay"  # the link state of the diagnostic where the replayed span begins ...
REPLAY_END = "replay_end"  # ... and where it ends


class ReplayLink(Protocol):
    """Sends a command's data (``send``) or any frame of the ground station's
    (``send_frame``), each returning the time it went; ``note`` records an event."""

    def send(self, data: bytes) -> float: ...

    def send_frame(self, can_id: int, data: bytes) -> float: ...

    def note(self, event: Event) -> None: ...


class Watch(Protocol):
    """The attitude feedback and every feedback message's time, as they come."""

    @property
    def samples(self) -> list[Sample]: ...

    @property
    def feedback_times(self) -> list[float]: ...

    def wait(self, done: Callable[[], bool], until: float) -> bool: ...


@dataclass
class Outcome:
    """How far a replay got: the alignment, when the span began and ended on the bench
    (Unix s), the frames sent and how late they went, and why it stopped early ('')."""

    arrival: Arrival | None = None
    began: float | None = None
    ended: float | None = None
    sent: int = 0
    commands: int = 0
    late_s: list[float] = field(default_factory=list)
    stopped: str = ""
    centred: bool | None = None

    @property
    def latest_s(self) -> float:
        return max(self.late_s, default=0.0)


def start_goals(attitude: Sample) -> Goals:
    """Where the flight began: its pitch and its yaw motor angle (from the nose)."""
    return ((PITCH, round(attitude.pitch, 2)), (MOTOR_YAW, round(attitude.motor_yaw, 2)))


class Player:
    """Replays spans over ``link``; ``outcome`` tells how far it got, also after Ctrl-C."""

    def __init__(
        self,
        link: ReplayLink,
        watch: Watch,
        *,
        source: str = "replay",
        clock: Clock = WALL_CLOCK,
        settings: Settings | None = None,
        progress: Callable[[Outcome, float], None] | None = None,
    ) -> None:
        self.link = link
        self.watch = watch
        self.source = source
        self.clock = clock
        self.settings = settings or Settings()
        self.progress = progress
        self.outcome = Outcome()
        self._ticked = 0.0
        self._open: tuple[Span, float] | None = None  # the span begun and not yet ended

    def play(self, span: Span, *, speed: float = 1.0, align: bool = True) -> Outcome:
        """Align (unless not ``align``), then send every frame of ``span`` at its time."""
        out = self.outcome = Outcome()
        clock = self.clock
        if not self.watch.wait(
            lambda: bool(self.watch.feedback_times), clock.monotonic() + FIRST_FEEDBACK_WAIT_S
        ):
            out.stopped = (
                f"no feedback from the gimbal in {FIRST_FEEDBACK_WAIT_S:g} s: is it on this "
                "link and powered? Nothing of the flight was sent"
            )
            return out
        if align and span.attitude is not None:
            out.arrival = self.align(start_goals(span.attitude))
            if not out.arrival.reached:
                out.stopped = (
                    f"the gimbal could not be brought to the flight's first attitude "
                    f"({describe(start_goals(span.attitude))}): {out.arrival.reason}; nothing "
                    "of the flight was sent (--no-align replays from where it is)"
                )
                return out
        out.began = clock.time()
        self.link.note(self._marker(span, speed, REPLAY))
        self._open = (span, speed)
        origin = clock.monotonic()
        for frame in span.frames:
            due = origin + (frame.time - span.start) / speed
            if not self._wait_until(due, origin):
                break
            self.link.send_frame(frame.can_id, frame.data)
            out.late_s.append(clock.monotonic() - due)
            out.sent += 1
            out.commands += frame.is_command
        if not out.stopped:  # the gimbal's answer to the last command, as long as the flight's
            commands = [f.time for f in span.frames if f.is_command]
            last = (commands[-1] - span.start) / speed if commands else 0.0
            after = self.settings.time_allowed_s + AFTER_DEADLINE_S
            self._wait_until(origin + max((span.end - span.start) / speed, last + after), origin)
        self.close_span()
        return out

    def close_span(self, stopped: str = "") -> None:
        """Mark the end of the replayed span in the recording (once; after Ctrl-C too,
        with ``stopped`` saying why)."""
        if self._open is None:
            return
        span, speed = self._open
        self._open = None
        self.outcome.stopped = self.outcome.stopped or stopped
        self.outcome.ended = self.clock.time()
        self.link.note(self._marker(span, speed, REPLAY_END))

    def align(self, goals: Goals) -> Arrival:
        """Bring the gimbal to ``goals``: the time a turn at the check's slowest passing
        slew takes, and the analysis' time allowed on top."""
        sample = self.watch.samples[-1] if self.watch.samples else None
        timeout = time_needed(goals, sample, Limits().min_slew_dps) + self.settings.time_allowed_s
        return bring_to(
            self.link,
            self.watch,
            goals,
            tolerance_deg=self.settings.tolerance_deg,
            timeout_s=timeout,
            clock=self.clock,
        )

    def centre(self, *, wait: bool) -> None:
        """Speeds 0, then ``forward`` (as the check leaves the gimbal); with ``wait``, until
        the feedback shows it centred (``outcome.centred``)."""
        allowed = self.settings.time_allowed_s + AFTER_DEADLINE_S
        centred = centre(
            self.link,
            self.watch,
            tolerance_deg=self.settings.tolerance_deg,
            timeout_s=allowed if wait else None,
            clock=self.clock,
        )
        if wait:
            self.outcome.centred = centred

    # -- time passing ----------------------------------------------------------------------

    def _wait_until(self, due: float, origin: float) -> bool:
        """Sleep until ``due`` (monotonic), looking at the feedback meanwhile; False when
        the gimbal went silent (``outcome.stopped`` says so)."""
        clock = self.clock
        while True:
            now = clock.monotonic()
            if self.progress is not None and now - self._ticked >= TICK_S:
                self._ticked = now
                self.progress(self.outcome, now - origin)
            silence = self._silence()
            if silence is not None:
                self.outcome.stopped = silence
                return False
            left = due - now
            if left <= 0:
                return True
            clock.sleep(min(left, SLICE_S))

    def _silence(self) -> str | None:
        times = self.watch.feedback_times
        if not times:
            return None
        quiet = self.clock.time() - times[-1]
        if quiet < SILENCE_S:
            return None
        out = self.outcome
        return (
            f"the gimbal went silent: no feedback for {quiet:.1f} s, after {out.sent:,} "
            f"frames ({out.commands:,} commands); the replay stopped"
        )

    def _marker(self, span: Span, speed: float, state: str) -> Event:
        words = f"{span.source}, {span.words()}, at {speed:g} times its speed"
        if state == REPLAY:
            detail = f"replay of {words} begins"
        else:
            out = self.outcome
            how = f"stopped: {out.stopped}" if out.stopped else "ended"
            detail = f"replay of {words} {how}: {out.sent:,} frames sent"
        return link_event(
            self.source,
            detail,
            state,
            at=self.clock.time(),
            flight=span.source,
            flight_from=round(span.start, 6),
            flight_to=round(span.end, 6),
            span_start_s=round(span.start_s, 3),
            span_end_s=round(span.end_s, 3),
            speed=speed,
        )
