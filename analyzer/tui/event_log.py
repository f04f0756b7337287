"""The monitor's log views: events numbered in arrival order, kept in time order."""

from __future__ import annotations

from collections import deque

from analyzer.protocol.types import TOPIC_COMMAND, TOPIC_DIAGNOSTICS, TOPIC_UAV_TEXT, Event

LOG_LIMIT = 2000  # entries kept per log view

# The command log view shows these topics; the "all" view every decoded topic.
COMMAND_VIEW_TOPICS = frozenset({TOPIC_COMMAND, TOPIC_DIAGNOSTICS, TOPIC_UAV_TEXT})


class LogEntry:
    """An event in a log view, numbered in arrival order (the views are in time order)."""

    __slots__ = ("event", "seq")

    def __init__(self, seq: int, event: Event) -> None:
        self.seq = seq
        self.event = event


def insert_in_time_order(log: deque[LogEntry], entry: LogEntry) -> None:
    """Append, or insert before newer entries: events can be reported after later ones.

    (A partial message is reported when it times out, with the time it started; a link
    change carries the wall clock.) Entries of equal time keep their arrival order.
    """
    t = entry.event.time
    if not log or log[-1].event.time <= t:
        log.append(entry)
        return
    if len(log) == log.maxlen:
        log.popleft()  # the oldest makes room, as an append would do
    i = len(log)
    while i > 0 and log[i - 1].event.time > t:
        i -= 1
    log.insert(i, entry)
