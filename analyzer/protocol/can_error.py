"""SocketCAN error frames (linux/can/error.h) in the words of can-utils' ``candump -e``.

An error frame carries its error classes in the CAN ID (the ``CAN_ERR_FLAG`` itself is
not part of the ``can_id`` given here) and the details in its 8 data bytes: the bit of a
lost arbitration (data[0]), controller problems (data[1]), protocol violation type and
location (data[2], data[3]), transceiver status (data[4]) and the TX / RX error counters
(data[6], data[7]). :func:`decode_error_frame` is a pure function of ID and data; it
never raises, and whatever does not fit the header becomes a ``problems`` entry.

An error frame with no class bits (an ASC ``ErrorFrame`` line, an adapter that encodes
errors its own way) is a well-formed ``unspecified`` error, whatever its data.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

CAN_ERR_TX_TIMEOUT = 0x001  # TX timeout (by netdevice driver)
CAN_ERR_LOSTARB = 0x002  # lost arbitration / data[0]
CAN_ERR_CRTL = 0x004  # controller problems / data[1]
CAN_ERR_PROT = 0x008  # protocol violations / data[2..3]
CAN_ERR_TRX = 0x010  # transceiver status / data[4]
CAN_ERR_ACK = 0x020  # received no ACK on transmission
CAN_ERR_BUSOFF = 0x040  # bus off
CAN_ERR_BUSERROR = 0x080  # bus error (may flood!)
CAN_ERR_RESTARTED = 0x100  # controller restarted
CAN_ERR_CNT = 0x200  # TX error counter / data[6], RX error counter / data[7]
CAN_ERR_DLC = 8

# Bit i of the class mask, of data[1] and of data[2]: can-utils' names (lib.c).
CLASS_NAMES = (
    "tx-timeout",
    "lost-arbitration",
    "controller-problem",
    "protocol-violation",
    "transceiver-status",
    "no-acknowledgement-on-tx",
    "bus-off",
    "bus-error",
    "restarted-after-bus-off",
    "error-counter-tx-rx",
)
KNOWN_CLASSES = (1 << len(CLASS_NAMES)) - 1
UNSPECIFIED = "unspecified"  # the class of an error frame that names none
UNKNOWN_CLASS = "unknown-class"  # class bits linux/can/error.h does not define
CONTROLLER_PROBLEMS = (
    "rx-overflow",
    "tx-overflow",
    "rx-error-warning",
    "tx-error-warning",
    "rx-error-passive",
    "tx-error-passive",
    "back-to-error-active",
)
PROTOCOL_TYPES = (
    "single-bit-error",
    "frame-format-error",
    "bit-stuffing-error",
    "tx-dominant-bit-error",
    "tx-recessive-bit-error",
    "bus-overload",
    "active-error",
    "error-on-tx",
)
# data[3]: the place in the frame where the protocol violation happened.
PROTOCOL_LOCATIONS = {
    0x03: "start-of-frame",
    0x02: "id.28-to-id.21",
    0x06: "id.20-to-id.18",
    0x04: "bit-srtr",
    0x05: "bit-ide",
    0x07: "id.17-to-id.13",
    0x0F: "id.12-to-id.5",
    0x0E: "id.4-to-id.0",
    0x0C: "bit-rtr",
    0x0D: "reserved-bit-1",
    0x09: "reserved-bit-0",
    0x0B: "data-length-code",
    0x0A: "data-field",
    0x08: "crc-sequence",
    0x18: "crc-delimiter",
    0x19: "acknowledge-slot",
    0x1B: "acknowledge-delimiter",
    0x1A: "end-of-frame",
    0x12: "intermission",
    0x11: "active-error-flag",
    0x13: "tolerate-dominant-bits",
    0x16: "passive-error-flag",
    0x17: "error-delimiter",
    0x1C: "overload-flag",
}
LOCATION_LIMIT = 32  # can-utils names locations 0..31 ("unspecified" where the header has none)
# data[4]: the wires' state as the transceiver sees it (CAN-H in the low, CAN-L in the high nibble).
TRANSCEIVER_STATES = {
    0x04: "canh-no-wire",
    0x05: "canh-short-to-bat",
    0x06: "canh-short-to-vcc",
    0x07: "canh-short-to-gnd",
    0x40: "canl-no-wire",
    0x50: "canl-short-to-bat",
    0x60: "canl-short-to-vcc",
    0x70: "canl-short-to-gnd",
    0x80: "canl-short-to-canh",
}
# The data byte each class explains its details in (the last of them for the counters).
_CLASS_BYTE = {CAN_ERR_LOSTARB: 0, CAN_ERR_CRTL: 1, CAN_ERR_PROT: 3, CAN_ERR_TRX: 4, CAN_ERR_CNT: 7}


@dataclass(frozen=True, slots=True)
class CanError:
    """One error frame, decoded; ``problems`` says why it does not fit linux/can/error.h."""

    text: str  # as ``candump -e`` explains it, e.g. ``controller-problem{rx-error-passive}``
    classes: tuple[str, ...]
    controller: tuple[str, ...] = ()
    protocol: tuple[str, ...] = ()
    location: str | None = None  # of a protocol violation
    transceiver: str | None = None
    lost_arbitration_bit: int | None = None  # None when unspecified
    tx_errors: int | None = None  # None when the frame does not report the counters
    rx_errors: int | None = None
    problems: tuple[str, ...] = field(default=())

    def fields(self) -> dict[str, Any]:
        """The JSON fields of its diagnostic (what the frame does not tell is left out)."""
        out: dict[str, Any] = {
            "error": self.text,
            "classes": list(self.classes),
            "controller": list(self.controller),
            "protocol": list(self.protocol),
            "location": self.location,
            "transceiver": self.transceiver,
            "lost_arbitration_bit": self.lost_arbitration_bit,
            "tx_errors": self.tx_errors,
            "rx_errors": self.rx_errors,
        }
        out = {key: value for key, value in out.items() if value is not None}
        if self.problems:
            out["malformed"] = "; ".join(self.problems)
        return out


def _bits(value: int, names: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(name for i, name in enumerate(names) if value >> i & 1)


def _counters(data: bytes) -> str:
    """``{{128}{136}}``: the TX and RX error counters as candump -e writes them."""
    return f"{{{{{data[6]}}}{{{data[7]}}}}}"


def decode_error_frame(can_id: int, data: bytes) -> CanError:
    """The error frame with class bits ``can_id`` (without CAN_ERR_FLAG) and ``data``."""
    classes = can_id & 0x1FFFFFFF
    if classes == 0:  # no SocketCAN class: whatever the bytes are, they are not its details
        return CanError(UNSPECIFIED, (UNSPECIFIED,))
    problems: list[str] = []
    if classes & ~KNOWN_CLASSES:
        problems.append(f"unknown error class bits 0x{classes & ~KNOWN_CLASSES:08X}")
    if len(data) != CAN_ERR_DLC:
        short = [
            CLASS_NAMES[mask.bit_length() - 1]
            for mask, index in _CLASS_BYTE.items()
            if classes & mask and len(data) <= index
        ]
        missing = f" (no details for {', '.join(short)})" if short else ""
        problems.append(f"{len(data)} data bytes; an error frame has {CAN_ERR_DLC}{missing}")
    padded = (bytes(data) + bytes(CAN_ERR_DLC))[:CAN_ERR_DLC]
    names = _bits(classes, CLASS_NAMES)
    parts: list[str] = []
    controller: tuple[str, ...] = ()
    protocol: tuple[str, ...] = ()
    location = transceiver = None
    lost_bit = None
    whole = len(data) >= CAN_ERR_DLC  # the counters are the last two bytes
    counters = whole and (bool(classes & CAN_ERR_CNT) or bool(padded[6] or padded[7]))
    for name in names:
        text = name
        if name == "lost-arbitration":
            text += f"{{at bit {padded[0]}}}"
            lost_bit = padded[0] or None
        elif name == "controller-problem":
            controller = _bits(padded[1], CONTROLLER_PROBLEMS)
            if padded[1] >> len(CONTROLLER_PROBLEMS):
                problems.append(f"unknown controller problem bits 0x{padded[1]:02X}")
            text += "{" + ",".join(controller) + "}"
        elif name == "protocol-violation":
            protocol = _bits(padded[2], PROTOCOL_TYPES)
            location = PROTOCOL_LOCATIONS.get(padded[3], UNSPECIFIED)
            if padded[3] >= LOCATION_LIMIT:
                problems.append(f"unknown protocol violation location 0x{padded[3]:02X}")
            shown = location if 0 < padded[3] < LOCATION_LIMIT else ""
            text += "{{" + ",".join(protocol) + "}{" + shown + "}}"
        elif name == "transceiver-status":
            if padded[4]:
                transceiver = TRANSCEIVER_STATES.get(padded[4], f"0x{padded[4]:02X}")
                text += "{" + transceiver + "}"
            else:
                transceiver = UNSPECIFIED
        elif name == "error-counter-tx-rx":
            text += _counters(padded) if whole else "{?}"
        parts.append(text)
    if counters and not classes & CAN_ERR_CNT:
        parts.append("error-counter-tx-rx" + _counters(padded))
    unknown = classes & ~KNOWN_CLASSES
    if unknown:
        parts.append(f"{UNKNOWN_CLASS}{{0x{unknown:08X}}}")
        names = (*names, UNKNOWN_CLASS)
    return CanError(
        ",".join(parts),
        names,
        controller,
        protocol,
        location,
        transceiver,
        lost_bit,
        padded[6] if counters else None,
        padded[7] if counters else None,
        tuple(problems),
    )
