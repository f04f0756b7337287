"""A python-can bus opened passively (nothing is ever transmitted), reopened when it fails."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable
from typing import Any, Protocol

from analyzer.errors import UsageError
from analyzer.library_log import LibraryLog, library_log
from analyzer.protocol.can_message import SOCKETCAN_ERROR_INTERFACES, frame_from_message
from analyzer.sources.reconnect import DeviceLink, Put, ReconnectingSource, error_words
from analyzer.sources.socketcan_links import bring_up, socketcan_down
from analyzer.sources.spec import CanSpec

RECV_POLL_S = 0.25  # how long one recv waits, so that close() is heard in time

# How each python-can interface is asked for listen-only (silent / monitor) mode.
# Interfaces not listed have no such option in python-can: they are opened normally and
# only ever read from. For socketcan, set listen-only on the link itself:
#   ip link set can0 type can bitrate 1000000 listen-only on
LISTEN_ONLY_OPTIONS: dict[str, dict[str, Any]] = {
    "slcan": {"listen_only": True},
    "vector": {"listen_only": True},
    "nixnet": {"listen_only": True},
    "kvaser": {"driver_mode": False},  # False = silent mode
    "cantact": {"monitor": True},
    "seeedstudio": {"operation_mode": "silent"},
    # pcan and systec take a BusState; filled in lazily because it needs the can import.
    "pcan": {"state": "PASSIVE"},
    "systec": {"state": "PASSIVE"},
}


class ReceivingBus(Protocol):
    """What a capture uses of a ``can.BusABC``: receive and shut down, never send."""

    def recv(self, timeout: float | None = None) -> Any: ...  # a can.Message or None

    def shutdown(self) -> None: ...


BusOpener = Callable[[CanSpec], ReceivingBus]


def listen_only_kwargs(interface: str) -> dict[str, Any]:
    """The python-can keyword arguments requesting listen-only mode, {} where there are none."""
    options = dict(LISTEN_ONLY_OPTIONS.get(interface, {}))
    if options.get("state") == "PASSIVE":
        import can

        options["state"] = can.BusState.PASSIVE
    return options


def bus_arguments(spec: CanSpec) -> dict[str, Any]:
    """Every keyword ``can.Bus`` gets for ``spec``: the same at the first open and each reopen."""
    kwargs: dict[str, Any] = {
        "interface": spec.interface,
        "channel": spec.channel,
        "receive_own_messages": False,
    }
    if spec.bitrate is not None:
        kwargs["bitrate"] = spec.bitrate
    if spec.interface == "gs_usb" and spec.channel.isdigit():
        kwargs["index"] = int(spec.channel)  # python-can 4.6 takes the device's number so
    kwargs.update(listen_only_kwargs(spec.interface))
    kwargs.update(spec.options)
    return kwargs


def open_bus(spec: CanSpec) -> ReceivingBus:
    """``can.Bus`` for ``spec``; an interface python-can does not know is a UsageError."""
    import can

    try:
        bus: ReceivingBus = can.Bus(**bus_arguments(spec))
        return bus
    except (can.CanInterfaceNotImplementedError, NotImplementedError) as exc:
        if spec.interface not in can.VALID_INTERFACES:
            known = ", ".join(sorted(can.VALID_INTERFACES))
            raise UsageError(
                f"unknown CAN interface {spec.interface!r}; python-can knows: {known}"
            ) from exc
        raise


class CanLink(DeviceLink):
    """One python-can bus at a time: only ``recv`` and ``shutdown`` are ever called on it
    (python-can buses are not thread-safe: ``recv`` polls, so ``close`` is heard)."""

    def __init__(self, spec: CanSpec, opener: BusOpener) -> None:
        self.spec = spec
        self.opener = opener
        self.description = str(spec)
        self.listen_only = bool(LISTEN_ONLY_OPTIONS.get(spec.interface))
        self._bus: ReceivingBus | None = None
        self._lock = threading.Lock()
        self.library_notes: list[str] = []  # what python-can logged while opening the bus

    def open(self) -> None:
        notes = LibraryLog()
        with library_log(notes):  # python-can logs while it imports a driver's module
            bus = self.opener(self.spec)
        self.library_notes = notes.take()
        channel = self.spec.channel
        if self.spec.interface == "socketcan" and socketcan_down(channel):
            # bound to a down interface, the socket would wait in silence
            with contextlib.suppress(Exception):
                bus.shutdown()
            raise ConnectionError(f"{channel} is down ({bring_up(channel)})")
        with self._lock:
            self._bus = bus

    def receive(self, put: Put, stopping: threading.Event) -> tuple[bool, str]:
        bus = self._bus
        if bus is None:
            return False, "not open"
        got_data = False
        channel = self.spec.channel
        # error frames of these interfaces carry linux/can/error.h classes in their ID
        socketcan_errors = self.spec.interface in SOCKETCAN_ERROR_INTERFACES
        while not stopping.is_set():
            try:
                msg = bus.recv(timeout=RECV_POLL_S)
            except Exception as exc:  # an unplugged adapter, an interface down, a driver error
                return got_data, error_words(exc)
            if msg is not None:
                got_data = True
                put(frame_from_message(msg, channel, socketcan_errors=socketcan_errors))
        return got_data, "capture stopped"

    def release(self) -> None:
        with self._lock:
            bus, self._bus = self._bus, None
        if bus is not None:
            with contextlib.suppress(Exception):  # an unplugged adapter cannot say goodbye
                bus.shutdown()

    def opened_words(self) -> str:
        mode = "listen-only" if self.listen_only else "receive-only"
        notes = "".join(f"; {note}" for note in self.library_notes)
        return f"opened {self.description} ({mode}){notes}"

    def cannot_open_words(self, reason: str) -> str:
        return f"cannot open {self.description}: {reason}{open_hint(self.spec, reason)}"


INTERFACES_HINT = "`gimbal-analyzer interfaces` lists the adapters this computer has"


def open_hint(spec: CanSpec, reason: str) -> str:
    """What to do when a bus cannot be opened because it is not there ('' otherwise)."""
    if spec.interface == "socketcan" and "Address family not supported" in reason:
        return f" (this computer has no SocketCAN, Linux's CAN sockets; {INTERFACES_HINT})"
    if "No such device" in reason:
        return f" (there is no {spec.channel}; {INTERFACES_HINT})"
    if "library not found" in reason or "not installed" in reason:
        return f" (the adapter's driver is missing; {INTERFACES_HINT})"
    return ""


class CanSource(ReconnectingSource):
    """Receive-only access to a python-can bus, opened again when it fails.

    Where python-can exposes a listen-only mode for the interface it is requested, so
    the adapter does not even acknowledge frames (see ``LISTEN_ONLY_OPTIONS``). A bus
    that cannot be opened at the start is a SourceError (or a UsageError for an
    interface python-can does not know); a bus that fails later (USB adapter unplugged,
    interface down, driver error) is shut down and reopened with the same arguments
    and the same backoff as ``tcp:`` (``analyzer.sources.reconnect``), while the
    capture goes on. ``open_bus`` replaces ``can.Bus`` (tests).
    """

    thread_name = "can"

    def __init__(
        self,
        spec: CanSpec,
        *,
        open_bus: BusOpener = open_bus,
        backoff_initial: float = 0.5,
        backoff_max: float = 10.0,
    ) -> None:
        link = CanLink(spec, open_bus)
        self.spec = spec
        self.bitrate = spec.bitrate or 1_000_000
        self.listen_only = link.listen_only
        super().__init__(
            link,
            source_name=spec.channel,  # the decoder names CAN events by channel
            open_now=True,
            backoff_initial=backoff_initial,
            backoff_max=backoff_max,
        )
