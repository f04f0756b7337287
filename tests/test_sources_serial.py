"""Serial source through pyserial's loop:// and through a pseudo-terminal."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from typing import Any

import pytest
import serial

from analyzer.errors import SourceError
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.types import LINK, Event, StreamChunk
from analyzer.sources import open_source
from analyzer.sources.serial_port import SerialSource
from analyzer.sources.spec import SerialSpec

DEADLINE_S = 5.0
CONTROL = wrap_control(bytes([0x0F, 0x07, 0, 0, 0, 0, 0, 0]))


def read_until(source: Any, done: Callable[[list[Any]], bool]) -> list[Any]:
    items: list[Any] = []
    deadline = time.monotonic() + DEADLINE_S
    while not done(items):
        assert time.monotonic() < deadline, f"timed out; got {items!r}"
        items.extend(source.read(0.05))
    return items


def stream(items: list[Any]) -> bytes:
    return b"".join(i.data for i in items if isinstance(i, StreamChunk))


def test_loop_url() -> None:
    source = open_source("serial:loop://@115200")
    assert isinstance(source, SerialSource)
    try:
        source.port.write(CONTROL)  # loop:// hands back what is written to it
        items = read_until(source, lambda got: stream(got) == CONTROL)
    finally:
        source.close()
    assert source.description == "serial:loop://@115200"
    assert all(i.source == "serial" for i in items if isinstance(i, StreamChunk))
    opened = items[0]
    assert isinstance(opened, Event) and opened.fields["kind"] == LINK
    assert opened.fields["detail"] == "opened loop:// at 115200 baud"


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pseudo-terminal")
def test_pty_device() -> None:
    master, slave = os.openpty()
    try:
        source = open_source(f"serial:{os.ttyname(slave)}@57600")
        try:
            os.write(master, CONTROL[:5])
            os.write(master, CONTROL[5:] + CONTROL)
            items = read_until(source, lambda got: stream(got) == CONTROL * 2)
        finally:
            source.close()
    finally:
        os.close(master)
        os.close(slave)
    assert len(stream(items)) == 48


def test_missing_device_is_a_source_error(tmp_path: Any) -> None:
    with pytest.raises(SourceError, match="cannot open serial:"):
        open_source(f"serial:{tmp_path}/ttyNONE@115200")


def test_a_port_failing_mid_capture_is_reopened() -> None:
    class Unplugged:
        in_waiting = 0

        def read(self, size: int) -> bytes:
            raise OSError(5, "Input/output error")

        def close(self) -> None:
            pass

    opened: list[SerialSpec] = []

    def open_port(spec: SerialSpec) -> Any:
        opened.append(spec)
        if len(opened) == 1:
            return Unplugged()
        if len(opened) == 2:
            raise OSError(2, "No such file or directory", spec.url)
        return serial.serial_for_url("loop://", timeout=0.05)

    spec = SerialSpec("/dev/ttyUSB9", 115200)
    source = SerialSource(spec, open_port=open_port, backoff_initial=0.01, backoff_max=0.02)
    try:
        items = read_until(source, lambda got: len(opened) == 3 and states(got)[-1:] == ["open"])
        source.port.write(CONTROL)
        items += read_until(source, lambda got: stream(got) == CONTROL)
    finally:
        source.close()
    assert opened == [spec] * 3
    assert states(items) == [
        "open",
        "lost",
        "reconnecting",
        "connect_failed",
        "reconnecting",
        "open",
    ]
    details = [e.fields["detail"] for e in items if isinstance(e, Event)]
    assert details[1] == "serial:/dev/ttyUSB9@115200 lost: Input/output error"
    assert details[3] == (
        "cannot open serial:/dev/ttyUSB9@115200: No such file or directory: /dev/ttyUSB9"
    )
    assert details[5].startswith("opened /dev/ttyUSB9 at 115200 baud again after ")


def states(items: list[Any]) -> list[str]:
    return [e.fields["state"] for e in items if isinstance(e, Event)]
