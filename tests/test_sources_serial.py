"""Serial source through pyserial's loop:// and through a pseudo-terminal."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from typing import Any

import pytest

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


def test_port_failure_ends_the_source() -> None:
    class Unplugged:
        in_waiting = 0

        def read(self, size: int) -> bytes:
            raise OSError(5, "Input/output error")

        def close(self) -> None:
            pass

    source = SerialSource(SerialSpec("/dev/ttyUSB9", 115200), port=Unplugged())
    items: list[Any] = []
    with pytest.raises(
        SourceError, match=r"serial:/dev/ttyUSB9@115200 failed: .*Input/output error"
    ):
        deadline = time.monotonic() + DEADLINE_S
        while time.monotonic() < deadline:
            items.extend(source.read(0.05))
    source.close()
    assert [e.fields["state"] for e in items if isinstance(e, Event)] == ["open", "lost"]
