"""``Listener``: a python-can listener that decodes each message and hands on the events."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

import can

from analyzer.api.decoding import Decoder
from analyzer.protocol.types import Event

__all__ = ["Listener"]

log = logging.getLogger("analyzer")


class Listener(can.Listener):
    """A ``can.Listener`` for ``can.Notifier(bus, [listener])``: every message received is
    decoded and each event it completes goes to ``callback(event)``.

    An exception inside (of the callback, or of decoding) never reaches the notifier,
    whose thread would stop: it goes to ``error_handler(exception)`` when given, else
    to the ``analyzer`` logger; ``errors`` counts them and ``last_error``
    keeps the latest. ``stop()`` (``notifier.stop()`` calls it) hands on, as
    diagnostics, what is still incomplete. ``channel`` names the bus when its messages
    do not.

    >>> import can
    >>> from analyzer import Listener, can_message
    >>> events = []
    >>> listener = Listener(events.append)
    >>> listener(can_message("forward"))  # what the notifier does with a received message
    >>> [(e.topic, e.fields["name"]) for e in events]
    [('/gimbal/command', 'forward')]
    >>> def broken(event):
    ...     raise RuntimeError("a bug in the callback")
    >>> careful = Listener(broken, error_handler=lambda exc: None)
    >>> careful(can_message("forward"))  # does not raise
    >>> careful.errors, str(careful.last_error)
    (1, 'a bug in the callback')
    """

    def __init__(
        self,
        callback: Callable[[Event], object],
        *,
        other_frames: bool = False,
        channel: str | None = None,
        error_handler: Callable[[Exception], object] | None = None,
    ) -> None:
        super().__init__()
        self.callback = callback
        self.decoder = Decoder(other_frames=other_frames)
        self.channel = channel
        self.error_handler = error_handler
        self.errors = 0
        self.last_error: Exception | None = None
        self._lock = threading.Lock()  # one message at a time, whoever calls

    def on_message_received(self, msg: can.Message) -> None:
        """Decode ``msg`` and call back with each event; never raises."""
        with self._lock:
            try:
                events = self.decoder.feed_message(msg, self.channel)
            except Exception as exc:  # a bug of the decoder must not stop the notifier
                self._failed(exc)
                return
            self._hand_on(events)

    def stop(self) -> None:
        """The end of the input: what is still incomplete goes to the callback."""
        with self._lock:
            try:
                events = self.decoder.close()
            except Exception as exc:
                self._failed(exc)
                return
            self._hand_on(events)

    def _hand_on(self, events: list[Event]) -> None:
        for event in events:
            try:
                self.callback(event)
            except Exception as exc:
                self._failed(exc)

    def _failed(self, exc: Exception) -> None:
        self.errors += 1
        self.last_error = exc
        handler = self.error_handler
        if handler is not None:
            try:
                handler(exc)
                return
            except Exception as second:
                exc = second
        log.error("gimbal-analyzer Listener: %s", exc, exc_info=exc)
