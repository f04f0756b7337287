"""Parse ``--source`` specs: ``can:``, ``tcp:``, ``proxy:``, ``serial:`` and ``file:`` forms."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

from analyzer.errors import UsageError

DEFAULT_IDU_HOST = "192.168.42.200"
DEFAULT_IDU_PORT = 2000
DEFAULT_CAN_BITRATE = 1_000_000
DEFAULT_SERIAL_BAUDRATE = 115_200
DEFAULT_PROXY_LISTEN_HOST = "0.0.0.0"
LOOPBACK_HOST = "127.0.0.1"

SOURCE_FORMS = (
    "can:INTERFACE:CHANNEL[@BITRATE][,KEY=VALUE...] (e.g. can:socketcan:can0, "
    "can:virtual:demo, can:vector:0@1000000,serial=12345), "
    "tcp:HOST:PORT (tcp:HOST uses port 2000, tcp:PORT means 127.0.0.1:PORT, "
    "tcp: alone the IDU at 192.168.42.200:2000), "
    "proxy:[LISTEN_HOST:]PORT->IDU_HOST:PORT (a LISTEN port alone listens on all interfaces), "
    "serial:DEVICE[@BAUD] (e.g. serial:/dev/ttyUSB0@115200), "
    "file:PATH"
)


@dataclass(frozen=True, slots=True)
class CanSpec:
    interface: str
    channel: str
    bitrate: int | None  # None: the interface has no bitrate (virtual) or none was given
    # python-can's own keyword arguments of the interface (a Vector device's ``serial``),
    # from ``,KEY=VALUE`` after the channel: digits as numbers, anything else as text
    options: tuple[tuple[str, int | str], ...] = ()

    def __str__(self) -> str:
        rate = f"@{self.bitrate}" if self.bitrate else ""
        extra = "".join(f",{key}={value}" for key, value in self.options)
        return f"can:{self.interface}:{self.channel}{rate}{extra}"


@dataclass(frozen=True, slots=True)
class TcpSpec:
    host: str
    port: int


@dataclass(frozen=True, slots=True)
class ProxySpec:
    listen_host: str
    listen_port: int
    idu_host: str
    idu_port: int


@dataclass(frozen=True, slots=True)
class SerialSpec:
    url: str
    baudrate: int


@dataclass(frozen=True, slots=True)
class FileSpec:
    path: str


SourceSpec = CanSpec | TcpSpec | ProxySpec | SerialSpec | FileSpec

# Interfaces without a bitrate setting of their own (set on the link, or none at all): no
# default bitrate is passed.
NO_BITRATE = frozenset({"virtual", "socketcan", "udp_multicast"})


class SpecError(UsageError):
    """A spec that does not parse; ``why`` says what is wrong with it, in a few words."""

    def __init__(self, spec: str, why: str) -> None:
        super().__init__(f"bad source {spec!r}: {why}; valid forms: {SOURCE_FORMS}")
        self.spec = spec
        self.why = why


def _bad(spec: str, why: str) -> SpecError:
    return SpecError(spec, why)


def _port(text: str, spec: str) -> int:
    if not text.isdigit() or not 0 <= int(text) <= 65535:
        raise _bad(spec, f"port {text!r} is not a number 0-65535")
    return int(text)


def split_host_port(text: str, spec: str, *, default_port: int | None = None) -> tuple[str, int]:
    """``HOST:PORT``, ``[V6ADDR]:PORT`` or (with a default port) ``HOST``."""
    if text.startswith("["):
        host, sep, rest = text[1:].partition("]")
        if not sep or not host:
            raise _bad(spec, f"unclosed '[' in {text!r}")
        if not rest:
            if default_port is None:
                raise _bad(spec, f"missing port in {text!r}")
            return host, default_port
        if not rest.startswith(":"):
            raise _bad(spec, f"expected ':PORT' after ']' in {text!r}")
        return host, _port(rest[1:], spec)
    host, sep, port = text.rpartition(":")
    if not sep:
        if default_port is None:
            raise _bad(spec, f"missing port in {text!r}")
        host, port = text, str(default_port)
    if not host:
        raise _bad(spec, f"missing host in {text!r}")
    if ":" in host:
        raise _bad(spec, f"write IPv6 addresses in brackets: [{host}]:{port}")
    return host, _port(port, spec)


def tcp_address(text: str, spec: str) -> tuple[str, int]:
    """The one grammar of a TCP address in every option (``--source``, ``--to``, ``--on``
    and the IDU side of a proxy): ``HOST:PORT``; ``HOST`` (port 2000); ``PORT`` alone
    (digits) is that port on loopback, 127.0.0.1, never a host named by a number."""
    if text.isdigit():
        return LOOPBACK_HOST, _port(text, spec)
    return split_host_port(text, spec, default_port=DEFAULT_IDU_PORT)


_OPTION = re.compile(r"([a-z_][a-z0-9_]*)=(.+)")


def _split_options(text: str) -> tuple[str, tuple[tuple[str, int | str], ...]]:
    """``0@1000000,serial=12345`` -> (``0@1000000``, (("serial", 12345),)): the trailing
    ``,KEY=VALUE`` parts; any other comma stays in the channel."""
    parts = text.split(",")
    options: list[tuple[str, int | str]] = []
    while len(parts) > 1 and (match := _OPTION.fullmatch(parts[-1])):
        key, value = match.groups()
        options.insert(0, (key, int(value) if value.isdigit() else value))
        parts.pop()
    return ",".join(parts), tuple(options)


def _split_rate(text: str) -> tuple[str, int | None]:
    """``NAME@123`` -> (NAME, 123); a trailing ``@`` part that is not digits stays in the name."""
    name, sep, rate = text.rpartition("@")
    if sep and rate.isdigit():
        return name, int(rate)
    return text, None


def parse_source(spec: str) -> SourceSpec:
    """Turn a ``--source`` string into a spec object; raise UsageError naming the valid forms."""
    kind, sep, rest = spec.partition(":")
    kind = kind.strip().lower()
    if not sep and kind != "tcp":
        raise _bad(spec, "missing 'KIND:'")
    parse = _PARSERS.get(kind)
    if parse is None:
        raise _bad(spec, f"unknown source kind {kind!r}")
    return parse(rest, spec)


def _can_source(rest: str, spec: str) -> CanSpec:
    interface, sep, channel = rest.partition(":")
    if not interface or not sep or not channel:
        raise _bad(spec, "CAN sources need an interface and a channel")
    channel, options = _split_options(channel)
    channel, bitrate = _split_rate(channel)
    if not channel:
        raise _bad(spec, "missing CAN channel")
    if bitrate is None and interface not in NO_BITRATE:
        bitrate = DEFAULT_CAN_BITRATE
    if bitrate is not None and bitrate <= 0:
        raise _bad(spec, "bitrate must be positive")
    return CanSpec(interface, channel, bitrate, options)


def _tcp_source(rest: str, spec: str) -> TcpSpec:
    if not rest:
        return TcpSpec(DEFAULT_IDU_HOST, DEFAULT_IDU_PORT)
    host, port = tcp_address(rest, spec)
    return TcpSpec(host, port)


def _proxy_source(rest: str, spec: str) -> ProxySpec:
    listen, sep, idu = rest.partition("->")
    if not sep or not listen or not idu:
        raise _bad(spec, "a proxy needs LISTEN->IDU_HOST:PORT")
    if listen.isdigit():
        listen_host, listen_port = DEFAULT_PROXY_LISTEN_HOST, _port(listen, spec)
    else:
        listen_host, listen_port = split_host_port(listen, spec)
    idu_host, idu_port = tcp_address(idu, spec)
    return ProxySpec(listen_host, listen_port, idu_host, idu_port)


def _serial_source(rest: str, spec: str) -> SerialSpec:
    url, baudrate = _split_rate(rest)
    if not url:
        raise _bad(spec, "missing serial device")
    if baudrate is not None and baudrate <= 0:
        raise _bad(spec, "baud rate must be positive")
    return SerialSpec(url, DEFAULT_SERIAL_BAUDRATE if baudrate is None else baudrate)


def _file_source(rest: str, spec: str) -> FileSpec:
    if not rest:
        raise _bad(spec, "missing file path")
    return FileSpec(rest)


# Each source kind's parser: the rest of the spec after "KIND:" (and the whole spec, for
# its errors) in, its spec out.
_PARSERS: dict[str, Callable[[str, str], SourceSpec]] = {
    "can": _can_source,
    "tcp": _tcp_source,
    "proxy": _proxy_source,
    "serial": _serial_source,
    "file": _file_source,
}
