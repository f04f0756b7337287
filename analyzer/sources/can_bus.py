"""A python-can bus opened passively: frames are received, nothing is ever transmitted."""

from __future__ import annotations

import contextlib
from typing import Any

from analyzer.errors import SourceError, UsageError
from analyzer.inputs.python_can import SOCKETCAN_ERROR_INTERFACES, frame_from_message
from analyzer.protocol.types import CanFrame
from analyzer.sources.base import MAX_ITEMS_PER_READ, SourceItem, link_event
from analyzer.sources.spec import CanSpec

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


def listen_only_kwargs(interface: str) -> dict[str, Any]:
    """The python-can keyword arguments requesting listen-only mode, {} where there are none."""
    options = dict(LISTEN_ONLY_OPTIONS.get(interface, {}))
    if options.get("state") == "PASSIVE":
        import can

        options["state"] = can.BusState.PASSIVE
    return options


class CanSource:
    """Receive-only access to a python-can bus.

    The bus object is private and only ``recv`` and ``shutdown`` are ever called on it;
    where python-can exposes a listen-only mode for the interface it is requested, so
    the adapter does not even acknowledge frames (see ``LISTEN_ONLY_OPTIONS``).
    """

    def __init__(self, spec: CanSpec, *, bus: Any = None) -> None:
        self.spec = spec
        self.bitrate = spec.bitrate or 1_000_000
        rate = f"@{spec.bitrate}" if spec.bitrate else ""
        self.description = f"can:{spec.interface}:{spec.channel}{rate}"
        self.source_name = spec.channel  # the decoder names CAN events by channel
        self.listen_only = bool(LISTEN_ONLY_OPTIONS.get(spec.interface))
        self._bus = bus if bus is not None else self._open(spec)
        self._closed = False
        self._announced = False
        self._pending_error: BaseException | None = None

    def _open(self, spec: CanSpec) -> Any:
        import can

        kwargs: dict[str, Any] = {"receive_own_messages": False}
        if spec.bitrate is not None:
            kwargs["bitrate"] = spec.bitrate
        kwargs.update(listen_only_kwargs(spec.interface))
        try:
            return can.Bus(interface=spec.interface, channel=spec.channel, **kwargs)
        except (can.CanInterfaceNotImplementedError, NotImplementedError) as exc:
            if spec.interface not in can.VALID_INTERFACES:
                known = ", ".join(sorted(can.VALID_INTERFACES))
                raise UsageError(
                    f"unknown CAN interface {spec.interface!r}; python-can knows: {known}"
                ) from exc
            raise SourceError(f"cannot open {self.description}: {exc}") from exc
        except Exception as exc:  # python-can, driver and OS errors all mean "cannot open"
            raise SourceError(f"cannot open {self.description}: {_one_line(exc)}") from exc

    def read(self, timeout: float) -> list[SourceItem]:
        if self._closed:
            raise EOFError
        if self._pending_error is not None:
            exc, self._pending_error = self._pending_error, None
            raise SourceError(f"{self.description} failed: {_one_line(exc)}") from exc
        out: list[SourceItem] = []
        if not self._announced:
            self._announced = True
            mode = "listen-only" if self.listen_only else "receive-only"
            out.append(link_event(self.source_name, f"opened {self.description} ({mode})", "open"))
        try:
            msg = self._bus.recv(timeout=max(0.0, timeout))
            while msg is not None:
                out.append(self._frame(msg))
                if len(out) >= MAX_ITEMS_PER_READ:
                    break
                msg = self._bus.recv(timeout=0.0)
        except Exception as exc:  # an unplugged adapter or a driver error ends the capture
            if out:
                # hand over what was read; the next read reports the failure
                self._pending_error = exc
                return out
            raise SourceError(f"{self.description} failed: {_one_line(exc)}") from exc
        return out

    def _frame(self, msg: Any) -> CanFrame:
        socketcan_errors = self.spec.interface in SOCKETCAN_ERROR_INTERFACES
        return frame_from_message(msg, self.spec.channel, socketcan_errors=socketcan_errors)

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(Exception):
            self._bus.shutdown()


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else exc.__class__.__name__
