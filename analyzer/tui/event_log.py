"""The monitor's log views: events numbered in arrival order, kept in time order; in the
command view a command repeated (a stick's gimbal_control every 50 ms) is one line."""

from __future__ import annotations

from collections import deque

from analyzer.protocol.types import TOPIC_COMMAND, TOPIC_DIAGNOSTICS, TOPIC_UAV_TEXT, Event

LOG_LIMIT = 2000  # entries kept per log view

# The command log view shows these topics; the "all" view every decoded topic.
COMMAND_VIEW_TOPICS = frozenset({TOPIC_COMMAND, TOPIC_DIAGNOSTICS, TOPIC_UAV_TEXT})


FOLD_GAP_S = 1.0  # a command less than this after the same one is folded into its line


class LogEntry:
    """An event in a log view, numbered in arrival order (the views are in time order).

    A folded entry stands for ``count`` commands, the first at ``start``; ``event`` is
    the last of them (its values are shown)."""

    __slots__ = ("count", "event", "seq", "start")

    def __init__(self, seq: int, event: Event) -> None:
        self.seq = seq
        self.event = event
        self.count = 1
        self.start = event.time


def fold_key(event: Event) -> tuple[object, ...]:
    """What makes two commands the same one repeated: name, source, direction and every
    worded field (zoom_in vs stop, the axis, the component); the numbers (speeds,
    angles) may change from one to the next."""
    words = tuple(
        sorted((k, v) for k, v in event.fields.items() if isinstance(v, str) and k != "raw")
    )
    return event.source, words


class CommandRuns:
    """Folds a command into the line of the same command just before it (no other command
    between, at most FOLD_GAP_S apart), as text mode leaves repeated commands out, so the
    diagnostics between a stick's commands stay in view."""

    def __init__(self) -> None:
        self._run: LogEntry | None = None
        self._key: tuple[object, ...] = ()

    def fold(self, entry: LogEntry) -> bool:
        """Whether ``entry`` (a command) went into the line before (else it starts one)."""
        event = entry.event
        key = fold_key(event)
        run = self._run
        if run is not None and key == self._key and 0 <= event.time - run.event.time < FOLD_GAP_S:
            run.count += 1
            run.event = event
            return True
        self._run, self._key = entry, key
        return False


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
