"""A USB serial adapter simulated on a pseudo-terminal: plugged in, unplugged, plugged in again.

``PtyDevice`` is the USB device: a pty whose slave is reached through a symlink named
like udev names it (``/dev/serial/by-id/usb-..-if00``, here in a temporary directory).
Unplugging closes the pty (a reader of the slave gets EIO, as from a USB adapter that
disappears) and removes the link; plugging in again makes a new pty behind the same
link. ``SlcanAdapter`` is a CANable / CANtact with slcan firmware on such a device,
answering the Lawicel commands the way that firmware does: ``C`` close, ``S0``-``S8``
bitrate (refused while open), ``O`` open, ``L`` open listen-only, ``V`` version,
``N`` serial number, ``t``/``T`` transmit (refused when closed or listen-only); ``\\r``
acknowledges, ``\\a`` (BEL) refuses. Received bus frames go to the host as ``t``/``T``
lines ending in ``\\r``, only while the channel is open. Every command the host sent is
kept in ``commands``, over every plug.
"""

from __future__ import annotations

import os
import struct
import threading
import time
from pathlib import Path

OK = b"\r"
REFUSED = b"\a"
BITRATES = {
    b"S0": 10_000,
    b"S1": 20_000,
    b"S2": 50_000,
    b"S3": 100_000,
    b"S4": 125_000,
    b"S5": 250_000,
    b"S6": 500_000,
    b"S7": 750_000,
    b"S8": 1_000_000,
}
DEADLINE_S = 10.0


def by_id_name(vendor: str, product: str, serial: str) -> str:
    """The name udev gives a USB serial interface under /dev/serial/by-id."""
    return f"usb-{vendor}_{product}_{serial}-if00"


class PtyDevice:
    """A serial device behind ``link`` that can be unplugged and plugged in again."""

    def __init__(self, link: Path) -> None:
        self.link = link
        self.master = -1
        self.slave = -1
        self.plugs = 0
        self._reader: threading.Thread | None = None
        self._unplugging = threading.Event()
        self.write_lock = threading.Lock()

    @property
    def plugged(self) -> bool:
        return self.master >= 0

    def plug(self) -> None:
        """A new pty behind the link (a new ttyACMn, the same by-id name)."""
        assert not self.plugged, "already plugged in"
        self.master, self.slave = os.openpty()
        import tty  # POSIX only: imported when a device is plugged

        tty.setraw(self.slave)  # no echo, no CR/LF translation, as a USB CDC-ACM port
        self.link.parent.mkdir(parents=True, exist_ok=True)
        self.link.symlink_to(os.ttyname(self.slave))
        self.plugs += 1
        self._unplugging.clear()
        self._reader = threading.Thread(target=self._read, name="pty-device", daemon=True)
        self._reader.start()

    def unplug(self) -> None:
        """The cable is pulled: the pty goes away and so does the link."""
        if not self.plugged:
            return
        self._unplugging.set()
        self.link.unlink()
        master, slave = self.master, self.slave
        self.master = self.slave = -1
        os.close(master)
        os.close(slave)
        if self._reader is not None:
            self._reader.join(DEADLINE_S)
        self.unplugged()

    def write(self, data: bytes) -> None:
        """Bytes from the device to the host (dropped when unplugged, as on a real cable)."""
        with self.write_lock:
            if self.plugged:
                os.write(self.master, data)

    def pending(self) -> int:
        """Bytes written to the host that the host has not read yet."""
        if not self.plugged:
            return 0
        import fcntl
        import termios

        raw = fcntl.ioctl(self.slave, termios.FIONREAD, struct.pack("i", 0))
        return int(struct.unpack("i", raw)[0])

    def wait_read(self, timeout: float = DEADLINE_S) -> None:
        """Wait until the host has read everything written to it (the kernel hands bytes
        written to the master on to the slave a moment later: nothing pending is believed
        only when seen twice, 50 ms apart)."""
        deadline = time.monotonic() + timeout
        calm = 0
        while calm < 2:
            time.sleep(0.05)
            calm = calm + 1 if not self.pending() else 0
            assert time.monotonic() < deadline, f"the host left {self.pending()} bytes unread"

    def _read(self) -> None:
        import select

        master = self.master
        while not self._unplugging.is_set():
            try:
                ready, _, _ = select.select([master], [], [], 0.05)
                if not ready:
                    continue
                data = os.read(master, 4096)
            except OSError:  # closed by unplug(), or nobody has the slave open
                if self._unplugging.is_set():
                    return
                time.sleep(0.01)
                continue
            if data:
                self.received(data)

    def received(self, data: bytes) -> None:
        """Bytes from the host (override)."""

    def unplugged(self) -> None:
        """Called after an unplug (override)."""

    def close(self) -> None:
        self.unplug()


class SlcanAdapter(PtyDevice):
    """An slcan (Lawicel) CAN adapter as CANable / CANtact firmware answers."""

    VERSION = b"V1013"  # hardware 10, software 13
    SERIAL_NUMBER = b"NA1B2"

    def __init__(self, link: Path) -> None:
        super().__init__(link)
        self.commands: list[bytes] = []
        self.bitrate: int | None = None
        self.mode = "closed"  # closed, open (normal) or listen-only
        self._pending = b""
        self.opened = threading.Event()

    def received(self, data: bytes) -> None:
        self._pending += data
        while True:
            line, sep, rest = self._pending.partition(b"\r")
            if not sep:
                return
            self._pending = rest
            self.commands.append(line)
            self.write(self.answer(line))

    def answer(self, command: bytes) -> bytes:
        """The firmware's answer to one command (without its ``\\r``)."""
        kind = command[:1]
        if command == b"":
            return OK  # an empty line: nothing to do
        if kind == b"C":
            self.mode = "closed"
            self.opened.clear()
            return OK
        if kind == b"S":
            if self.mode != "closed" or command not in BITRATES:
                return REFUSED
            self.bitrate = BITRATES[command]
            return OK
        if kind in (b"O", b"L"):
            if self.mode != "closed" or self.bitrate is None:
                return REFUSED
            self.mode = "open" if kind == b"O" else "listen-only"
            self.opened.set()
            return OK
        if kind == b"V":
            return self.VERSION + OK
        if kind == b"N":
            return self.SERIAL_NUMBER + OK
        if kind in (b"t", b"T"):
            if self.mode != "open":
                return REFUSED
            return (b"z" if kind == b"t" else b"Z") + OK
        return REFUSED

    def unplugged(self) -> None:
        self.mode = "closed"
        self.bitrate = None  # the firmware starts over at power-up
        self._pending = b""
        self.opened.clear()

    def wait_open(self, timeout: float = DEADLINE_S) -> None:
        """Wait until the host has opened the channel (``O`` or ``L``)."""
        assert self.opened.wait(timeout), f"never opened; commands: {self.commands!r}"

    def frame(self, can_id: int, data: bytes, *, extended: bool = True) -> None:
        """A frame received on the bus, handed to the host (only while the channel is open)."""
        if self.mode == "closed":
            return
        head = f"T{can_id:08X}" if extended else f"t{can_id:03X}"
        self.write(f"{head}{len(data)}{data.hex().upper()}".encode() + OK)

    @property
    def transmit_requests(self) -> list[bytes]:
        """Every ``t`` / ``T`` (or remote ``r`` / ``R``) command the host sent."""
        return [c for c in self.commands if c[:1] in (b"t", b"T", b"r", b"R")]
