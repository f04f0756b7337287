"""The CAN adapters and serial ports of this machine, each with the ``--source`` that reads it."""

from __future__ import annotations

import contextlib
import logging
import os
import sys
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from analyzer.sources.can_bus import LISTEN_ONLY_OPTIONS
from analyzer.sources.reconnect import error_words
from analyzer.sources.socketcan_links import socketcan_links
from analyzer.sources.spec import (
    DEFAULT_CAN_BITRATE,
    DEFAULT_SERIAL_BAUDRATE,
    NO_BITRATE,
    CanSpec,
)

# python-can "interfaces" that are no adapter: software buses, and its own serial
# protocol (which lists every serial port; those are listed below as serial ports).
NOT_ADAPTERS = frozenset({"virtual", "udp_multicast", "serial"})
# Not searched: socketcand servers on the network (finding one takes 4 s of listening).
NOT_SEARCHED = NOT_ADAPTERS | {"socketcand"}
# What of python-can's detected config a --source keeps to open the same channel again:
# a Vector channel's number counts within its device, named by its serial number.
KEPT_OPTIONS: dict[str, tuple[str, ...]] = {"vector": ("serial",)}
BY_ID = "/dev/serial/by-id"
DETECT_TIMEOUT_S = 5.0

# USB serial devices that are slcan (Lawicel) CAN adapters, by USB vendor:product.
SLCAN_ADAPTERS: dict[tuple[int, int], str] = {
    (0x16D0, 0x117E): "CANable / CANtact with slcan firmware",
    (0x0403, 0xFFA8): "LAWICEL CANUSB",
    (0x04D8, 0x000A): "USBtin",
}


@dataclass(frozen=True, slots=True)
class CanAdapter:
    """A channel python-can found, with the ``--source`` that records from it."""

    interface: str
    channel: str
    source: str
    listen_only: str  # how passive reception is obtained, in words
    state: str = ""  # socketcan: "up" or "down"
    config: Mapping[str, Any] = field(default_factory=dict)  # python-can's detected config

    def to_dict(self) -> dict[str, Any]:
        return {
            "interface": self.interface,
            "channel": self.channel,
            "source": self.source,
            "listen_only": self.listen_only,
            "state": self.state or None,
            "config": {k: v if isinstance(v, str | int | float | bool) else str(v)
                       for k, v in self.config.items()},
        }  # fmt: skip


@dataclass(frozen=True, slots=True)
class SerialPort:
    """A serial port pyserial found, with the ``--source`` lines for it."""

    device: str
    stable_path: str  # /dev/serial/by-id/... when there is one (survives a replug)
    description: str
    vid: int | None
    pid: int | None
    serial_number: str | None
    manufacturer: str | None
    product: str | None
    slcan: str  # the kind of slcan CAN adapter it is, "" when not known as one

    @property
    def path(self) -> str:
        return self.stable_path or self.device

    @property
    def usb(self) -> str:
        """``16d0:117e`` (vendor:product), "" for a port that is not USB."""
        if self.vid is None or self.pid is None:
            return ""
        return f"{self.vid:04x}:{self.pid:04x}"

    @property
    def serial_source(self) -> str:
        return f"serial:{self.path}@{DEFAULT_SERIAL_BAUDRATE}"

    @property
    def slcan_source(self) -> str:
        return f"can:slcan:{self.path}@{DEFAULT_CAN_BITRATE}"

    def to_dict(self) -> dict[str, Any]:
        return {
            "device": self.device,
            "stable_path": self.stable_path or None,
            "description": self.description,
            "usb": self.usb or None,
            "vid": self.vid,
            "pid": self.pid,
            "serial_number": self.serial_number,
            "manufacturer": self.manufacturer,
            "product": self.product,
            "slcan_adapter": self.slcan or None,
            "source": self.slcan_source if self.slcan else self.serial_source,
            "serial_source": self.serial_source,
            "slcan_source": self.slcan_source,
        }


def listen_only_words(interface: str, channel: str) -> str:
    """How a capture from this interface stays off the bus, in a few words."""
    if interface == "socketcan":
        return (
            f"set on the link: sudo ip link set {channel} type can bitrate "
            f"{DEFAULT_CAN_BITRATE} listen-only on"
        )
    if LISTEN_ONLY_OPTIONS.get(interface):
        return "requested from the adapter (it does not even acknowledge frames)"
    return "python-can has none for this interface: opened normally, only read"


def can_source(interface: str, channel: str, config: Mapping[str, Any] | None = None) -> str:
    """The --source of a detected channel (with what ``KEPT_OPTIONS`` keeps of ``config``)."""
    options = tuple(
        (key, config[key])
        for key in KEPT_OPTIONS.get(interface, ())
        if config is not None and isinstance(config.get(key), int | str) and config[key] != ""
    )
    rate = None if interface in NO_BITRATE else DEFAULT_CAN_BITRATE
    return str(CanSpec(interface, channel, rate, options))


def gs_usb_configs(problems: list[str], platform: str | None = None) -> list[dict[str, Any]]:
    """gs_usb / candleLight adapters, numbered as python-can's gs_usb interface opens
    them (``GsUsb.scan()`` of the gs_usb package, through pyusb and libusb), which has no
    detection of its own. Nothing when python-can[gs-usb] is not installed, and nothing on
    Linux, whose gs_usb driver makes them SocketCAN interfaces (listed as those)."""
    if (platform or sys.platform).startswith("linux"):
        return []
    try:
        from gs_usb.gs_usb import GsUsb
    except ImportError:
        return []
    try:
        devices = list(GsUsb.scan())
    except Exception as exc:  # no libusb backend, no permission
        problems.append(f"gs_usb: detection failed: {error_words(exc)}")
        return []
    found: list[dict[str, Any]] = []
    for index, device in enumerate(devices):
        config: dict[str, Any] = {"interface": "gs_usb", "channel": str(index)}
        with contextlib.suppress(Exception):  # reading a string descriptor may be refused
            config["serial"] = str(device.serial_number)
        with contextlib.suppress(Exception):
            config["bus"], config["address"] = int(device.bus), int(device.address)
        found.append(config)
    return found


def python_can_configs(
    problems: list[str], timeout: float = DETECT_TIMEOUT_S
) -> list[dict[str, Any]]:
    """python-can's ``detect_available_configs``, without the warnings of every backend
    that is not installed (they are no news to someone asking what is plugged in). A
    backend whose detection fails is asked alone, and what went wrong is added to
    ``problems``; the others are listed all the same."""
    import can
    from can.interfaces import BACKENDS

    quiet = logging.getLogger("can")
    level = quiet.level
    quiet.setLevel(logging.CRITICAL)
    searched = [name for name in BACKENDS if name not in NOT_SEARCHED]
    try:
        try:
            return [dict(c) for c in can.detect_available_configs(searched, timeout=timeout)]
        except Exception:  # one backend's driver failed: find which, keep the rest
            found: list[dict[str, Any]] = []
            for name in searched:
                try:
                    found += [dict(c) for c in can.detect_available_configs(name, timeout)]
                except Exception as exc:
                    problems.append(f"python-can {name}: detection failed: {error_words(exc)}")
            return found
    finally:
        quiet.setLevel(level)


def can_adapters(
    configs: Iterable[Mapping[str, Any]], links: Mapping[str, str]
) -> list[CanAdapter]:
    """The adapters among python-can's configs, and the SocketCAN links it left out."""
    out: list[CanAdapter] = []
    seen: set[str] = set()  # sources: a channel of two devices differs by their serial
    for config in configs:
        interface = str(config.get("interface", ""))
        channel = str(config.get("channel", ""))
        if not interface or not channel or interface in NOT_ADAPTERS:
            continue
        source = can_source(interface, channel, config)
        if source in seen:
            continue
        seen.add(source)
        state = links.get(channel, "") if interface == "socketcan" else ""
        out.append(
            CanAdapter(
                interface,
                channel,
                source,
                listen_only_words(interface, channel),
                state,
                dict(config),
            )
        )
    for name, state in links.items():
        if can_source("socketcan", name) not in seen:
            out.append(
                CanAdapter(
                    "socketcan",
                    name,
                    can_source("socketcan", name),
                    listen_only_words("socketcan", name),
                    state,
                    {"interface": "socketcan", "channel": name},
                )
            )
    return out


def by_id_links(directory: str = BY_ID) -> dict[str, str]:
    """Device -> its stable /dev/serial/by-id name (udev's, from the USB serial number)."""
    out: dict[str, str] = {}
    with contextlib.suppress(OSError):
        for name in sorted(os.listdir(directory)):
            path = os.path.join(directory, name)
            out.setdefault(os.path.realpath(path), path)
    return out


def serial_ports(ports: Sequence[Any], stable: Mapping[str, str]) -> list[SerialPort]:
    """pyserial's ``ListPortInfo`` entries, as SerialPort (USB ports first, by device)."""
    out = []
    for port in ports:
        vid, pid = getattr(port, "vid", None), getattr(port, "pid", None)
        device = str(port.device)
        description = str(getattr(port, "description", "") or "")
        out.append(
            SerialPort(
                device=device,
                stable_path=stable.get(os.path.realpath(device), ""),
                description="" if description == "n/a" else description,
                vid=vid,
                pid=pid,
                serial_number=getattr(port, "serial_number", None),
                manufacturer=getattr(port, "manufacturer", None),
                product=getattr(port, "product", None),
                slcan=SLCAN_ADAPTERS.get((vid, pid), "") if vid and pid else "",
            )
        )
    out.sort(key=lambda p: (p.vid is None, p.device))
    return out


def pyserial_ports() -> list[Any]:
    from serial.tools import list_ports

    return list(list_ports.comports())


@dataclass(slots=True)
class Inventory:
    """What ``interfaces`` shows: CAN adapters and serial ports."""

    can: list[CanAdapter]
    serial: list[SerialPort]
    problems: list[str] = field(default_factory=list)  # detections that failed, in words

    def to_dict(self) -> dict[str, Any]:
        return {
            "can": [a.to_dict() for a in self.can],
            "serial": [p.to_dict() for p in self.serial],
            "problems": list(self.problems),
        }


def detect() -> Inventory:
    """Look at this machine: python-can's adapters, SocketCAN links, pyserial's ports."""
    problems: list[str] = []
    return Inventory(
        can_adapters(python_can_configs(problems) + gs_usb_configs(problems), socketcan_links()),
        serial_ports(pyserial_ports(), by_id_links()),
        problems,
    )
