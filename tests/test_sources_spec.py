"""Parsing of --source specs: every documented form, defaults, and one-line errors for bad ones."""

from __future__ import annotations

import pytest

from analyzer.errors import UsageError
from analyzer.sources import open_source
from analyzer.sources.spec import (
    CanSpec,
    FileSpec,
    ProxySpec,
    SerialSpec,
    TcpSpec,
    parse_source,
)


@pytest.mark.parametrize(
    ("spec", "expected"),
    [
        ("can:socketcan:can0", CanSpec("socketcan", "can0", None)),
        ("can:slcan:/dev/ttyACM0@1000000", CanSpec("slcan", "/dev/ttyACM0", 1_000_000)),
        ("can:slcan:/dev/ttyACM0", CanSpec("slcan", "/dev/ttyACM0", 1_000_000)),
        ("can:pcan:PCAN_USBBUS1", CanSpec("pcan", "PCAN_USBBUS1", 1_000_000)),
        ("can:pcan:PCAN_USBBUS1@500000", CanSpec("pcan", "PCAN_USBBUS1", 500_000)),
        ("can:virtual:demo", CanSpec("virtual", "demo", None)),
        (
            "can:slcan:socket://127.0.0.1:5000",
            CanSpec("slcan", "socket://127.0.0.1:5000", 1_000_000),
        ),
        ("tcp:192.168.42.200:2000", TcpSpec("192.168.42.200", 2000)),
        ("tcp:127.0.0.1:5555", TcpSpec("127.0.0.1", 5555)),
        ("tcp:idu.local", TcpSpec("idu.local", 2000)),
        ("tcp:[::1]:2000", TcpSpec("::1", 2000)),
        ("tcp:", TcpSpec("192.168.42.200", 2000)),
        ("tcp", TcpSpec("192.168.42.200", 2000)),
        (
            "proxy:0.0.0.0:2000->192.168.42.200:2000",
            ProxySpec("0.0.0.0", 2000, "192.168.42.200", 2000),
        ),
        ("proxy:127.0.0.1:0->127.0.0.1:9", ProxySpec("127.0.0.1", 0, "127.0.0.1", 9)),
        ("proxy:2000->192.168.42.200:2000", ProxySpec("0.0.0.0", 2000, "192.168.42.200", 2000)),
        ("serial:/dev/ttyUSB0@115200", SerialSpec("/dev/ttyUSB0", 115200)),
        ("serial:/dev/ttyUSB0", SerialSpec("/dev/ttyUSB0", 115200)),
        ("serial:loop://@9600", SerialSpec("loop://", 9600)),
        ("file:flight.log", FileSpec("flight.log")),
        ("file:/tmp/a:b.log", FileSpec("/tmp/a:b.log")),
    ],
)
def test_valid_specs(spec: str, expected: object) -> None:
    assert parse_source(spec) == expected


@pytest.mark.parametrize(
    "spec",
    [
        "",
        "can0",
        "bogus:thing",
        "can:virtual",
        "can::can0",
        "tcp:host:notaport",
        "tcp:host:70000",
        "tcp:::1:2000",
        "proxy:2000",
        "proxy:->1.2.3.4:5",
        "serial:",
        "serial:@9600",
        "file:",
    ],
)
def test_bad_specs_name_the_valid_forms(spec: str) -> None:
    with pytest.raises(UsageError) as info:
        parse_source(spec)
    message = str(info.value)
    assert "\n" not in message
    for form in ("can:INTERFACE:CHANNEL", "tcp:HOST:PORT", "proxy:", "serial:", "file:PATH"):
        assert form in message


def test_replay_speed_only_for_files() -> None:
    with pytest.raises(UsageError):
        open_source("tcp:127.0.0.1:1", replay_speed=1.0)


def test_unknown_can_interface_is_a_usage_error() -> None:
    with pytest.raises(UsageError, match="unknown CAN interface"):
        open_source("can:nosuchinterface:x")


def test_missing_replay_file_is_a_usage_error(tmp_path: object) -> None:
    with pytest.raises(UsageError, match="no such file"):
        open_source(f"file:{tmp_path}/missing.log")
