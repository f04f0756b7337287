"""Test files written the way other tools write them, holding the frames of a candump log.

- ``ardupilot_log``: an ArduPilot DataFlash log as AP_Logger writes it with
  ``CAN_P1_OPTIONS`` bit 0 (LogAllFrames): the FMT records of every message type first,
  UNIT / MULT / FMTU, PARM, MSG, then GPS records at 5 Hz and one ``CANF`` record per
  frame (layouts of libraries/AP_Logger, AP_GPS and AP_CANManager LogStructure.h;
  frames as AP_CANManager::can_logging_callback fills the record).
- ``lua_log``: CANF records as the CAN logging Lua applet writes them through
  ``logger.write('CANF', 'Id,DLC,FC,B0,...', 'IBIBBBBBBBB', ...)``: AP_Logger puts the
  TimeUS column in front and writes the FMT record when the script first logs.
- ``sll_pcap``: ``tcpdump -i any -w`` on a host with can0: LINUX_SLL (113) or
  LINUX_SLL2 (276) headers, protocol 0x000C, the SocketCAN frame with its CAN ID in
  host byte order (little-endian here), as the kernel hands it to the socket.
- ``savvycan_csv``: SavvyCAN's native CSV (FrameFileIO::saveNativeCSVFile).

The writers are independent of the readers under test: only the formats are shared.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import dpkt

from analyzer.inputs import open_input
from analyzer.inputs.dataflash.gps_time import utc_to_gps
from analyzer.protocol.types import CanFrame

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "flight-candump.log"
HEAD = b"\xa3\x95"
_CODES = {
    "b": "b", "B": "B", "h": "h", "H": "H", "i": "i", "I": "I", "f": "f", "d": "d",
    "n": "4s", "N": "16s", "Z": "64s", "c": "h", "C": "H", "e": "i", "E": "I",
    "L": "i", "M": "B", "q": "q", "Q": "Q",
}  # fmt: skip

# (type, name, format, columns, units, multipliers) as an ArduCopter 4.5 build numbers them
FMT, UNIT, FMTU, MULT, PARM, GPS, MSG, CANF, CAFD = 128, 177, 178, 179, 64, 65, 91, 200, 201
MESSAGES = {
    FMT: ("FMT", "BBnNZ", "Type,Length,Name,Format,Columns", "", ""),
    UNIT: ("UNIT", "QbZ", "TimeUS,Id,Label", "s--", "F--"),
    FMTU: ("FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds", "s---", "F---"),
    MULT: ("MULT", "Qbd", "TimeUS,Id,Mult", "s--", "F--"),
    PARM: ("PARM", "QNff", "TimeUS,Name,Value,Default", "s---", "F---"),
    GPS: (
        "GPS",
        "QBBIHBcLLeffffB",
        "TimeUS,I,Status,GMS,GWk,NSats,HDop,Lat,Lng,Alt,Spd,GCrs,VZ,Yaw,U",
        "s#-s-S-DUmnhnh-",
        "F--C-0BGGB000--",
    ),
    MSG: ("MSG", "QZ", "TimeUS,Message", "s-", "F-"),
    CANF: ("CANF", "QBIBBBBBBBBB", "TimeUS,Bus,Id,DLC,B0,B1,B2,B3,B4,B5,B6,B7", "s#----------", "F-----------"),
    CAFD: ("CAFD", "QBIBQQQQQQQQ", "TimeUS,Bus,Id,DLC,D0,D1,D2,D3,D4,D5,D6,D7", "s#----------", "F-----------"),
}  # fmt: skip
EFF, RTR = 1 << 31, 1 << 30


def flight_frames() -> list[CanFrame]:
    """The 629 frames of samples/flight-candump.log, as its candump reader gives them."""
    with open_input(str(SAMPLE)) as reader:
        return [item for item in reader if isinstance(item, CanFrame)]


class DataFlashWriter:
    """Records of a DataFlash log: ``A3 95 <type>`` and the packed columns."""

    def __init__(self) -> None:
        self.out = bytearray()
        self.layouts: dict[int, tuple[str, struct.Struct]] = {}

    def fmt(self, kind: int, name: str, fmt: str, columns: str) -> None:
        body = struct.Struct("<" + "".join(_CODES[c] for c in fmt))
        self.layouts[kind] = (fmt, body)
        self.record(FMT, kind, 3 + body.size, name.encode(), fmt.encode(), columns.encode())

    def record(self, kind: int, *values: object) -> int:
        """Append a record; returns its byte offset."""
        body = struct.Struct("<BB4s16s64s") if kind == FMT else self.layouts[kind][1]
        at = len(self.out)
        self.out += HEAD + bytes([kind]) + body.pack(*values)
        return at


def start_log(writer: DataFlashWriter, extra: list[int]) -> None:
    """What AP_Logger writes first: every format, units and multipliers, parameters."""
    kinds = [
        UNIT,
        FMTU,
        MULT,
        PARM,
        MSG,
        *(k for k in extra if k not in (UNIT, FMTU, MULT, PARM, MSG)),
    ]
    writer.record(FMT, FMT, 89, b"FMT", b"BBnNZ", b"Type,Length,Name,Format,Columns")
    writer.layouts[FMT] = ("BBnNZ", struct.Struct("<BB4s16s64s"))
    for kind in kinds:
        name, fmt, columns, _units, _mults = MESSAGES[kind]
        writer.fmt(kind, name, fmt, columns)
    for ident, label in ((ord("s"), b"s"), (ord("#"), b"instance"), (ord("-"), b"")):
        writer.record(UNIT, 1000, ident, label)
    for ident, mult in ((ord("F"), 1e-6), (ord("-"), 0.0), (ord("C"), 1e-3)):
        writer.record(MULT, 1000, ident, mult)
    for kind in kinds:
        units, mults = MESSAGES[kind][3:]
        if units:
            writer.record(FMTU, 1010, kind, units.encode(), mults.encode())
    for name, value in (("CAN_P1_DRIVER", 1.0), ("CAN_P1_OPTIONS", 1.0), ("CAN_D1_PROTOCOL", 1.0)):
        writer.record(PARM, 1020, name.encode(), value, 0.0)
    writer.record(MSG, 1030, b"ArduCopter V4.5.7 (2a3dc4b7)")


def gps_record(
    writer: DataFlashWriter, time_us: int, status: int, week: int, week_ms: int, lat: int
) -> None:
    """A GPS record of instance 0 at ``lat`` (degrees x 1e7), 14 satellites, in use."""
    writer.record(
        GPS, time_us, 0, status, week_ms, week, 14, 70, lat, 85455940, 48812, 0.1, 0.0, 0.0, 0.0, 1
    )


def ardupilot_log(
    frames: list[CanFrame], boot_utc: float, gps: bool = True
) -> tuple[bytes, list[int]]:
    """The frames as CANF records on bus 0, boot at ``boot_utc``; GPS at 5 Hz, the first
    two without a fix (week 0). Returns the log and each frame's record offset."""
    writer = DataFlashWriter()
    start_log(writer, [GPS, CANF, CAFD])
    offsets = []
    next_gps = 0
    for frame in frames:
        time_us = round((frame.time - boot_utc) * 1e6)
        while gps and next_gps * 200_000 <= time_us:
            gps_us = next_gps * 200_000
            week, week_ms = utc_to_gps(boot_utc + gps_us / 1e6) if next_gps >= 2 else (0, 0)
            status = 3 if next_gps >= 2 else 1
            gps_record(writer, gps_us, status, week, week_ms, 473977420)
            next_gps += 1
        ident = frame.can_id | (EFF if frame.extended else 0) | (RTR if frame.is_remote else 0)
        data = frame.data.ljust(8, b"\0")
        offsets.append(writer.record(CANF, time_us, 0, ident, len(frame.data), *data))
    return bytes(writer.out), offsets


def lua_log(frames: list[CanFrame], boot_utc: float, kind: int = 254) -> bytes:
    """The frames as a Lua script's CANF records (no GPS in this log)."""
    writer = DataFlashWriter()
    start_log(writer, [])
    for count, frame in enumerate(frames):
        time_us = round((frame.time - boot_utc) * 1e6)
        if count == 0:  # AP_Logger writes the format when the script first logs it
            writer.fmt(kind, "CANF", "QIBIBBBBBBBB", "TimeUS,Id,DLC,FC,B0,B1,B2,B3,B4,B5,B6,B7")
        ident = frame.can_id | (EFF if frame.extended else 0)
        writer.record(kind, time_us, ident, len(frame.data), count, *frame.data.ljust(8, b"\0"))
    return bytes(writer.out)


def socketcan_frame(frame: CanFrame, order: str = "<") -> bytes:
    """struct can_frame with the CAN ID in the given byte order: id, len, pad, res, len8_dlc."""
    ident = frame.can_id | (EFF if frame.extended else 0)
    return struct.pack(order + "IBBBB", ident, len(frame.data), 0, 0, 0) + frame.data.ljust(
        8, b"\0"
    )


def sll_pcap(
    path: Path, frames: list[CanFrame], link: int, ifindex: int = 5, ng: bool = False
) -> Path:
    """``tcpdump -i any -w path`` on a host where can0 (interface ``ifindex``) carried the
    frames (``ng``: pcapng, as dumpcap / Wireshark write ``-i any``)."""
    with path.open("wb") as handle:
        writer: Any = (
            dpkt.pcapng.Writer(handle, snaplen=262144, linktype=link)
            if ng
            else dpkt.pcap.Writer(handle, snaplen=262144, linktype=link)
        )
        for frame in frames:
            packet = socketcan_frame(frame)
            if link == 113:  # packet type, ARPHRD_CAN, address length, address, protocol
                header = struct.pack(">HHH8sH", 0, 280, 0, b"", 0x000C)
            else:  # protocol, reserved, interface index, ARPHRD_CAN, packet type, address length, address
                header = struct.pack(">HHIHBB8s", 0x000C, 0, ifindex, 280, 0, 0, b"")
            writer.writepkt(header + packet, ts=frame.time)
    return path


def python_can_log(path: Path, frames: list[CanFrame]) -> Path:
    """The frames written by python-can's ``can.Logger`` (the format from the suffix)."""
    import can

    with can.Logger(str(path)) as logger:
        for f in frames:
            logger.on_message_received(
                can.Message(
                    timestamp=f.time,
                    arbitration_id=f.can_id,
                    data=f.data,
                    is_extended_id=f.extended,
                )
            )
    return path


def savvycan_csv(frames: list[CanFrame]) -> str:
    """SavvyCAN's native CSV: microsecond times, 8-digit hex IDs, eight data columns."""
    lines = ["Time Stamp,ID,Extended,Dir,Bus,LEN,D1,D2,D3,D4,D5,D6,D7,D8"]
    for frame in frames:
        data = "".join(f"{b:02X}," for b in frame.data.ljust(8, b"\0"))
        lines.append(
            f"{round(frame.time * 1e6)},{frame.can_id:08X},{'true' if frame.extended else 'false'},"
            f"Rx,0,{len(frame.data)},{data}"
        )
    return "\n".join(lines) + "\n"
