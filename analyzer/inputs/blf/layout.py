"""The byte layout of Vector BLF files, as Vector's ``binlog_objects.h`` documents it.

A file starts with a header (``LOGG``, its own size, the measurement's start as a
SYSTEMTIME). Objects follow, each with a base header (``LOBJ``, header size, header
version, object size, object type) and, after it, the rest of its header:

- version 1 (``VBLObjectHeader``): flags, client index, object version, time stamp;
- version 2 (``VBLObjectHeader2``): flags, time stamp status, object version, time
  stamp, original time stamp;
- version 3 (``VBLVarObjectHeader``, objects that grow with later versions): flags,
  size of the static part, object version, time stamp.

The flags say the time stamp's unit (10 us or 1 ns); the object's own fields start
after the header (its header size). Objects of type LOG_CONTAINER hold the others,
zlib-compressed or not; an object may start in one container and end in the next.
After an object comes ``size % 4`` bytes of padding (what python-can writes and reads).
"""

from __future__ import annotations

import datetime
import struct
from decimal import Decimal

FILE_SIGNATURE = b"LOGG"
OBJECT_SIGNATURE = b"LOBJ"
# signature, header size, application (4), binlog version (4), file size, uncompressed
# size, object count, objects read, measurement start and last object (SYSTEMTIME each)
FILE_HEADER = struct.Struct("<4sLBBBBBBBBQQLL8H8H")
BASE_HEADER = struct.Struct("<4sHHLL")  # signature, header size, version, size, type
OBJECT_HEADER = struct.Struct("<LHHQ")  # versions 1 and 3: flags, (index | size), version, time
OBJECT_HEADER_2 = struct.Struct("<LBxHQQ")  # flags, status, version, time, original time
CONTAINER_HEADER = struct.Struct("<H6xL4x")  # compression method, uncompressed size
# The least header size of each header version (the base header and the rest).
HEADER_SIZES = {1: BASE_HEADER.size + OBJECT_HEADER.size, 2: 40, 3: 32}
TIME_OFFSET = 24  # the time stamp's offset in every version
TIME_TEN_MICROS = 1  # flags value: time stamps in 10 us (else in 1 ns)

NO_COMPRESSION = 0
ZLIB_DEFLATE = 2

# Object types (``BL_OBJ_TYPE_*``) this reader takes; the words for every type below.
CAN_MESSAGE = 1
CAN_ERROR = 2
LOG_CONTAINER = 10
CAN_ERROR_EXT = 73
CAN_MESSAGE2 = 86
CAN_FD_MESSAGE = 100
CAN_FD_MESSAGE_64 = 101
CAN_FD_ERROR_64 = 104
CAN_MESSAGES = (CAN_MESSAGE, CAN_MESSAGE2)

CAN_MESSAGE_DATA = struct.Struct("<HBBL8s")  # channel, flags, DLC, ID, data
CAN_ERROR_DATA = struct.Struct("<HH")  # channel, length
CAN_ERROR_EXT_DATA = struct.Struct("<HHLBBBxLLH2x8s")  # channel ... DLC, ..., ID, ..., data
CAN_FD_DATA = struct.Struct("<HBBLLBBB5x64s")  # channel, flags, DLC, ID, ..., FD flags, valid
CAN_FD_64_DATA = struct.Struct("<BBBBLLLLLLLHBBL")  # channel, DLC, valid, ..., ID, ..., flags
CAN_FD_ERROR_64_DATA = struct.Struct("<BB")  # channel, DLC
EXTENDED_ID = 0x80000000  # in a message's ID field
REMOTE = 0x80  # message flags: a remote frame
TRANSMITTED = 0x01  # message flags: sent, not received
FD_64_REMOTE, FD_64_FD = 0x0010, 0x1000  # CAN_FD_MESSAGE_64 flags
CAN_FD_LENGTHS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)

TYPE_NAMES = {
    CAN_MESSAGE: "CAN messages",
    CAN_ERROR: "CAN error frames",
    LOG_CONTAINER: "log containers",
    CAN_ERROR_EXT: "CAN error frames",
    CAN_MESSAGE2: "CAN messages",
    CAN_FD_MESSAGE: "CAN FD messages",
    CAN_FD_MESSAGE_64: "CAN FD messages",
    CAN_FD_ERROR_64: "CAN FD error frames",
    3: "CAN overload frames",
    4: "CAN driver statistics",
    5: "application triggers",
    6: "environment variables",
    7: "environment variables",
    8: "environment variables",
    9: "environment variables",
    **dict.fromkeys(range(11, 22), "LIN objects"),
    **dict.fromkeys((22, 23, 24, 25, *range(32, 40), 67, 68, 69, 70, 95), "MOST objects"),
    **dict.fromkeys((*range(76, 86),), "MOST objects"),
    **dict.fromkeys((29, 30, 40, 41, 45, *range(47, 51), 66), "FlexRay objects"),
    **dict.fromkeys((*range(54, 65), 75, 87, 88, 89, 105), "LIN objects"),
    31: "CAN driver errors",
    44: "CAN driver sync events",
    46: "GPS events",
    51: "real-time clock events",
    55: "J1708 messages",
    56: "J1708 messages",
    65: "application texts (channel names, comments)",
    **dict.fromkeys((71, 102, 103, 114, 120, 121, 122, 123), "Ethernet objects"),
    72: "system variables",
    74: "CAN driver errors",
    90: "serial events",
    91: "driver overrun events",
    92: "event comments",
    93: "WLAN objects",
    94: "WLAN objects",
    96: "global markers",
    **dict.fromkeys((97, 98, 106, 107, 109), "AFDX objects"),
    99: "K-Line status events",
    **dict.fromkeys((110, 111, 112, 113), "ARINC 429 objects"),
    115: "restore point containers",
    118: "test structure events",
    119: "diagnostic request interpretations",
    124: "function bus objects",
    125: "data lost markers",
    126: "data lost markers",
    127: "water mark events",
    128: "trigger conditions",
}


def kind_of(object_type: int) -> str:
    """Words for the objects of a type (Vector's ``BL_OBJ_TYPE_*``)."""
    return TYPE_NAMES.get(object_type, f"objects of type {object_type}")


def start_time(systemtime: tuple[int, ...]) -> float:
    """The measurement's start (a SYSTEMTIME, UTC) in seconds since 1970; 0.0 when it is
    no date (python-can's ``systemtime_to_timestamp``, so both give the same times)."""
    year, month, _, day, hour, minute, second, millis = systemtime
    try:
        moment = datetime.datetime(
            year, month, day, hour, minute, second, millis * 1000, tzinfo=datetime.timezone.utc
        )
    except ValueError:
        return 0.0
    return moment.timestamp()


def stamp_seconds(stamp: int, flags: int) -> float:
    """An object's time stamp in seconds, exactly as python-can works it out (a decimal
    product rounded once)."""
    factor = _TEN_MICROS if flags == TIME_TEN_MICROS else _NANOS
    return float(Decimal(stamp) * factor)


_TEN_MICROS, _NANOS = Decimal("1e-5"), Decimal("1e-9")
