"""The state of a live source's link in words, folded from its ``link`` diagnostics.

Shared by the monitor's status bar and the plain ``record`` status line, so both say the
same thing: "connected to ...", "cannot connect to ...: connection refused; retrying in
1.5 s", "connection lost: ... (gone 3.2 s, since 10:00:01.253Z); connecting again", and
once a lost link is back, when it was lost and when it came back. Time comes from the
events and the ``now`` the caller gives; nothing here reads a clock.
"""

from __future__ import annotations

from collections.abc import Iterable

from analyzer.protocol.types import LINK, TOPIC_DIAGNOSTICS, Event
from analyzer.sources.base import OVERFLOW
from analyzer.timefmt import UTC, TimeZone

GOOD_STATES = frozenset({"open", "connected", "gs_connected"})
WAIT_STATES = frozenset({"listening", "reconnecting", "connecting"})
PROBLEM_STATES = frozenset({"connect_failed", "lost", "refused"})
RETRY_STATE = "reconnecting"
LOST_STATE = "lost"


class LinkStatus:
    """The last link state change, and the failure a pending retry follows."""

    __slots__ = ("back_at", "detail", "lost_at", "problem", "retry_at", "state")

    def __init__(self) -> None:
        self.state = ""  # e.g. connected, connect_failed, lost, reconnecting, listening
        self.detail = ""  # the words of that change
        self.problem = ""  # the last failure's words, kept while a retry is pending
        self.retry_at: float | None = None  # when the pending retry is due (event time)
        self.lost_at: float | None = None  # when a link that was up went down (event time)
        self.back_at: float | None = None  # when it came back after such a loss

    def fold(self, events: Iterable[Event]) -> None:
        for event in events:
            if event.topic == TOPIC_DIAGNOSTICS and event.fields.get("kind") == LINK:
                self.note(event)

    def note(self, event: Event) -> None:
        """Take in one ``link`` diagnostic (an ``overflow`` note is no change of state)."""
        state = str(event.fields.get("state") or "")
        if state == OVERFLOW:
            return
        detail = str(event.fields.get("detail", ""))
        if state == LOST_STATE and (self.lost_at is None or self.back_at is not None):
            self.lost_at, self.back_at = event.time, None  # down since now
        elif state in GOOD_STATES and self.lost_at is not None and self.back_at is None:
            self.back_at = event.time  # up again
        if state == RETRY_STATE:
            retry = event.fields.get("retry_in_s")
            self.retry_at = event.time + float(retry) if isinstance(retry, int | float) else None
        else:
            self.retry_at = None
            self.problem = detail if state in PROBLEM_STATES else ""
        self.state = state
        self.detail = detail

    @property
    def seen(self) -> bool:
        return bool(self.state or self.detail)

    @property
    def good(self) -> bool:
        return self.state in GOOD_STATES

    @property
    def failing(self) -> bool:
        """The link is down: the last change was a failure, or a retry after one."""
        return self.state in PROBLEM_STATES or bool(self.state == RETRY_STATE and self.problem)

    def describe(self, now: float, zone: TimeZone = UTC) -> str:
        """The link in words at time ``now`` (a pending retry counts down; a lost link
        says since when, and once back, when it was lost and when it came back: in ``zone``)."""
        if self.good and self.back_at is not None and self.lost_at is not None:
            lost, back = zone.format_clock(self.lost_at), zone.format_clock(self.back_at)
            return f"{self.detail} (lost {lost}, back {back})"
        if self.state in PROBLEM_STATES:
            return self.detail + self._gone(now, zone)
        if self.state != RETRY_STATE:
            return self.detail or self.state
        if self.retry_at is None:
            retry = self.detail
        elif now >= self.retry_at:
            retry = "connecting again"
        else:
            retry = f"retrying in {self.retry_at - now:.1f} s"
        return f"{self.problem}{self._gone(now, zone)}; {retry}" if self.problem else retry

    def _gone(self, now: float, zone: TimeZone) -> str:
        if self.lost_at is None:
            return ""
        since = zone.format_clock(self.lost_at)
        return f" (gone {max(0.0, now - self.lost_at):.1f} s, since {since})"
