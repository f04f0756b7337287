"""BLF files made by hand as Vector's ``binlog_objects.h`` lays them out, for the tests.

python-can writes CAN messages, error frames and CAN FD messages with object header
version 1 in zlib containers. CANoe writes more: other header versions (2; 3 in
CANoe 15's default files), CAN_MESSAGE2 and CAN_FD_MESSAGE_64 objects, objects of
other buses and kinds (LIN, Ethernet, application texts, global markers), stored
containers, and older loggers objects outside containers. These functions make each of
those, byte by byte, with python-can's ``blf.py`` as the reference for what it reads.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterable
from typing import Any

from analyzer.inputs.blf.layout import (
    BASE_HEADER,
    CAN_ERROR,
    CAN_ERROR_EXT,
    CAN_FD_64_DATA,
    CAN_FD_DATA,
    CAN_FD_MESSAGE,
    CAN_FD_MESSAGE_64,
    CAN_MESSAGE,
    CAN_MESSAGE2,
    CONTAINER_HEADER,
    FILE_HEADER,
    LOG_CONTAINER,
    OBJECT_HEADER,
    OBJECT_HEADER_2,
)

NANOS = 2  # object flags: time stamps in nanoseconds
TEN_MICROS = 1
APP_TEXT = 65
LIN_MESSAGE = 11
ETHERNET_FRAME = 71
GLOBAL_MARKER = 96
START = (2024, 5, 2, 14, 10, 0, 0, 0)  # SYSTEMTIME: 2024-05-14 10:00:00.000 UTC
START_TIME = 1715680800.0


def blf_object(
    kind: int,
    body: bytes,
    *,
    stamp: int = 0,
    version: int = 1,
    flags: int = NANOS,
    size: int | None = None,
) -> bytes:
    """One object: its header in ``version`` 1, 2 or 3 (any other number: a version-1
    layout under that number), ``body`` and the padding python-can writes (size % 4)."""
    if version == 2:
        rest = OBJECT_HEADER_2.pack(flags, 0, 0, stamp, stamp)
    else:  # 1: client index, 3: size of the static part; both 0 here
        rest = OBJECT_HEADER.pack(flags, 0, 0, stamp)
    header_size = BASE_HEADER.size + len(rest)
    length = header_size + len(body) if size is None else size
    head = BASE_HEADER.pack(b"LOBJ", header_size, version, length, kind)
    return head + rest + body + bytes(len(body) % 4)


def can_message(
    can_id: int,
    data: bytes,
    *,
    channel: int = 1,
    extended: bool = True,
    remote: bool = False,
    sent: bool = False,
    dlc: int | None = None,
    second: bool = False,
) -> bytes:
    """The body of a CAN_MESSAGE (or CAN_MESSAGE2, with its frame length and bit count)."""
    flags = (0x80 if remote else 0) | (1 if sent else 0)
    ident = can_id | (0x80000000 if extended else 0)
    length = len(data) if dlc is None else dlc
    body = struct.pack("<HBBL8s", channel, flags, length, ident, data.ljust(8, b"\0"))
    return body + struct.pack("<LBBH", 131, 131, 0, 0) if second else body


def can_fd_64(can_id: int, data: bytes, *, valid: int | None = None, channel: int = 1) -> bytes:
    """The body of a CAN_FD_MESSAGE_64 (an FD frame with bit rate switch), ``valid`` bytes
    claimed (more than ``data`` holds: CANoe pads with zeros)."""
    dlc = next(
        i
        for i, n in enumerate((0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64))
        if n >= len(data)
    )
    fields = CAN_FD_64_DATA.pack(
        channel,
        dlc,
        len(data) if valid is None else valid,
        0,
        can_id | 0x80000000,
        0,
        0x1000 | 0x2000,
        0,
        0,
        0,
        0,
        0,
        0,
        0,
        0,
    )
    return fields + data


def can_fd(can_id: int, data: bytes, *, channel: int = 1) -> bytes:
    """The body of a CAN_FD_MESSAGE (what python-can writes for an FD frame)."""
    dlc = 9 if len(data) == 12 else len(data)
    return CAN_FD_DATA.pack(channel, 0, dlc, can_id | 0x80000000, 0, 0, 1, len(data), data)


def can_error_ext(channel: int = 1) -> bytes:
    return struct.pack("<HHLBBBxLLH2x8s", channel, 0, 0, 0, 0, 8, 0, 0x20000004, 0, bytes(8))


def can_error(channel: int = 1) -> bytes:
    return struct.pack("<HH", channel, 0)


def app_text(text: str) -> bytes:
    encoded = text.encode()
    return struct.pack("<LLLL", 2, 0, len(encoded), 0) + encoded


def other_objects() -> list[tuple[int, bytes]]:
    """Objects that carry no CAN frame, of kinds a CANoe log holds, with their types."""
    return [
        (APP_TEXT, app_text("CAN1;gimbal bus")),
        (LIN_MESSAGE, struct.pack("<HBB8sBBBBH", 1, 0x21, 8, bytes(range(8)), 0, 0, 0, 0, 0)),
        (ETHERNET_FRAME, bytes(6) + bytes(6) + struct.pack("<HHHHHQ", 1, 0, 0x800, 0, 20, 0)),
        (GLOBAL_MARKER, struct.pack("<LLL3xBLLL12x", 0, 0, 0, 0, 1, 1, 0) + b"gm"),
    ]


def blf_file(
    objects: Iterable[bytes],
    *,
    containers: str = "zlib",
    container_size: int = 128 * 1024,
    start: tuple[int, ...] = START,
) -> bytes:
    """A whole file: header, then the objects in containers of ``container_size``
    uncompressed bytes (an object may end in the next one), ``zlib`` or ``stored``;
    ``none``: the objects at the top level, as older loggers write them."""
    data = b"".join(objects)
    body = b""
    if containers == "none":
        body = data
    else:
        for at in range(0, len(data), container_size):
            part = data[at : at + container_size]
            method = 2 if containers == "zlib" else 0
            payload = zlib.compress(part) if method else part
            size = BASE_HEADER.size + CONTAINER_HEADER.size + len(payload)
            body += BASE_HEADER.pack(b"LOBJ", BASE_HEADER.size, 1, size, LOG_CONTAINER)
            body += CONTAINER_HEADER.pack(method, len(part)) + payload + bytes(size % 4)
    header_size = 144
    header = FILE_HEADER.pack(
        b"LOGG",
        header_size,
        5,
        0,
        0,
        0,
        2,
        6,
        8,
        1,
        header_size + len(body),
        header_size + len(data),
        0,
        0,
        *start,
        *start,
    )
    return header + bytes(header_size - len(header)) + body


__all__ = [
    "CAN_ERROR",
    "CAN_ERROR_EXT",
    "CAN_FD_MESSAGE",
    "CAN_FD_MESSAGE_64",
    "CAN_MESSAGE",
    "CAN_MESSAGE2",
]


def blf_of_columns(frames: Any, container_size: int = 128 * 1024) -> bytes:
    """Classic data frames (``FrameColumns``) as a BLF file of CAN_MESSAGE objects, made
    with numpy (a long log in a second, python-can's writer takes a minute)."""
    import numpy as np

    record = np.dtype(
        [
            ("signature", "S4"),
            ("header_size", "<u2"),
            ("version", "<u2"),
            ("size", "<u4"),
            ("type", "<u4"),
            ("flags", "<u4"),
            ("client", "<u2"),
            ("object_version", "<u2"),
            ("stamp", "<u8"),
            ("channel", "<u2"),
            ("message_flags", "u1"),
            ("dlc", "u1"),
            ("id", "<u4"),
            ("data", "u1", (8,)),
        ]
    )
    objects = np.zeros(len(frames), record)
    objects["signature"], objects["header_size"], objects["version"] = b"LOBJ", 32, 1
    objects["size"], objects["type"], objects["flags"] = 48, CAN_MESSAGE, NANOS
    objects["stamp"] = np.rint((frames.time - START_TIME) * 1e9).astype(np.uint64)
    objects["channel"] = frames.channel + 1
    objects["message_flags"] = np.where(frames.direction == 2, 1, 0)
    objects["dlc"] = frames.length
    objects["id"] = frames.can_id | np.where(frames.extended, 0x80000000, 0)
    objects["data"] = frames.data
    data = objects.tobytes()
    return blf_file([data], container_size=container_size)
