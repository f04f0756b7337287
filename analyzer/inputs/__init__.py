"""Capture file readers, one module per format, and ``open_input`` to pick the right one."""

from __future__ import annotations

import os
import re
from collections.abc import Iterable

from analyzer.errors import UsageError
from analyzer.inputs.base import InputItem, InputReader, open_binary
from analyzer.inputs.savvycan import SAVVYCAN_HEADER_START
from analyzer.inputs.textlines import GZIP_MAGIC, TolerantGunzip
from analyzer.protocol.ids import TCP_PORT

__all__ = ["FORMATS", "InputItem", "InputReader", "detect_format", "open_input"]

# --format values and what they read.
FORMATS: dict[str, str] = {
    "candump": "candump -L log or candump screen output (.log; '-' = standard input)",
    "asc": "Vector ASC (.asc) through python-can",
    "blf": "Vector BLF (.blf) through python-can",
    "trc": "PCAN-View TRC (.trc) through python-can",
    "csv": "python-can CSV (.csv)",
    "mf4": "ASAM MDF4 (.mf4) through python-can (needs asammdf)",
    "pcap": "pcap / pcapng capture of the IDU's TCP link or of a CAN bus (.pcap, .pcapng)",
    "stream": "raw byte dump of a TCP or UART stream (.bin)",
    "dataflash": "ArduPilot DataFlash log with CANF / CAFD records (.bin, .BIN)",
    "savvycan": "SavvyCAN / GVRET native CSV (.csv)",
    "mcap": "MCAP recording of this project, or a ROS 2 bag's can_msgs/msg/Frame topics (.mcap)",
    "rosbag": "ROS 1 bag (.bag) or rosbag2 sqlite3 storage (.db3): can_msgs/Frame topics",
}
ALIASES = {
    "log": "candump",
    "pcapng": "pcap",
    "bin": "stream",
    "raw": "stream",
    "ardupilot": "dataflash",
    "gvret": "savvycan",
}
EXTENSIONS = {
    ".log": "candump",
    ".candump": "candump",
    ".asc": "asc",
    ".blf": "blf",
    ".trc": "trc",
    ".csv": "csv",
    ".mf4": "mf4",
    ".pcap": "pcap",
    ".pcapng": "pcap",
    ".cap": "pcap",
    ".bin": "stream",
    ".raw": "stream",
    ".mcap": "mcap",
    ".bag": "rosbag",
    ".db3": "rosbag",
}
AMBIGUOUS = frozenset({".bin", ".csv"})
SNIFF_BYTES = 4096
_PCAP_MAGICS = (
    b"\xd4\xc3\xb2\xa1",
    b"\xa1\xb2\xc3\xd4",
    b"\x4d\x3c\xb2\xa1",
    b"\xa1\xb2\x3c\x4d",
    b"\x0a\x0d\x0d\x0a",  # pcapng
)

_CANDUMP_LOG = re.compile(rb"^\(\d+(?:\.\d+)?\)\s+\S+\s+[0-9A-Fa-f]{1,8}##?\S*", re.M)
_CANDUMP_SCREEN = re.compile(
    rb"^\s*(?:\([^)]*\)\s+)?\S+\s+(?:[RT]X\s+\S\s+\S\s+)?[0-9A-Fa-f]{1,8}\s+\[\d{1,2}\]", re.M
)


def normalise_format(fmt: str) -> str:
    """A --format value -> one of FORMATS; UsageError naming the valid ones."""
    name = fmt.strip().lower().lstrip(".")
    name = ALIASES.get(name, name)
    if name not in FORMATS:
        raise UsageError(f"unknown format {fmt!r}; valid: {', '.join(FORMATS)}")
    return name


def detect_format(path: str) -> str:
    """The format of a file from its name, else from its first bytes."""
    name = os.path.basename(path).lower()
    if name.endswith(".gz"):
        name = name[:-3]
    ext = os.path.splitext(name)[1]
    if ext in AMBIGUOUS:  # a .bin is a DataFlash log or a raw dump; .csv has two layouts
        try:
            head = _head(path)
        except UsageError:  # unreadable: the reader of the extension's format says why
            return EXTENSIONS[ext]
        return sniff_format(head) or EXTENSIONS[ext]
    if ext in EXTENSIONS:
        return EXTENSIONS[ext]
    found = sniff_format(_head(path))
    if found is None:
        raise UsageError(
            f"cannot tell the format of {path} from its name or content; "
            f"give --format ({', '.join(FORMATS)})"
        )
    return found


def sniff_format(head: bytes) -> str | None:
    """Recognise a format from the first few KiB of a file (None when unsure)."""
    if head[:4] in _PCAP_MAGICS:
        return "pcap"
    if head[:5] == b"\x89MCAP":
        return "mcap"
    if head.startswith((b"#ROSBAG V2.0\n", b"SQLite format 3\0")):
        return "rosbag"
    if head[:4] == b"LOGG":
        return "blf"
    if head[:2] == b"\xeb\x90":
        return "stream"
    if head[:2] == b"\xa3\x95":  # a DataFlash record header: its reader looks closer
        from analyzer.inputs.dataflash import looks_like_dataflash  # (not at each start-up)

        if looks_like_dataflash(head):
            return "dataflash"
    text = head.lstrip(b"\xef\xbb\xbf")
    if _CANDUMP_LOG.search(text) or _CANDUMP_SCREEN.search(text):
        return "candump"
    lowered = text[:512].lower()
    if lowered.startswith(b"date ") or b"\nbase hex" in lowered or b"\nbase dec" in lowered:
        return "asc"
    if lowered.startswith(b";$fileversion") or lowered.startswith(b";   start time"):
        return "trc"
    if lowered.startswith(b"timestamp,arbitration_id"):
        return "csv"
    if lowered.startswith(SAVVYCAN_HEADER_START):
        return "savvycan"
    return None


def _head(path: str) -> bytes:
    """The first SNIFF_BYTES of a file, decompressed when it is gzip (as much of them as
    decompresses: a damaged gzip file is the reader's to report, with its diagnostic)."""
    with open_binary(path) as handle:
        head = handle.read(SNIFF_BYTES)
        if head[:2] != GZIP_MAGIC:
            return head
        handle.seek(0)
        unpacked = b""
        try:
            for block in TolerantGunzip(handle).read_blocks():
                unpacked += block
                if len(unpacked) >= SNIFF_BYTES:
                    break
        except OSError:
            pass
    return unpacked[:SNIFF_BYTES]


def open_input(
    path: str,
    fmt: str | None = None,
    port: int = TCP_PORT,
    *,
    wanted_ids: Iterable[int] | None = None,
    stored: bool = False,
) -> InputReader:
    """Open a capture file (``-`` = standard input) for reading items.

    Iterating the result gives ``CanFrame`` / ``StreamChunk`` items and ``Event``
    diagnostics for unreadable lines or records; ``size_bytes`` / ``position_bytes``
    tell how far it got. ``wanted_ids`` lets the candump reader skip frames with other
    IDs cheaply (they are still counted). ``stored`` reads the events an MCAP recording
    holds instead of its raw frames (only for MCAP). Unknown or unreadable files raise
    UsageError.
    """
    name = normalise_format(fmt) if fmt else None
    if stored and (path == "-" or (name or detect_format(path)) != "mcap"):
        raise UsageError(f"--stored reads MCAP recordings; {path} is not one")
    if path == "-":
        from analyzer.inputs.stdin import StdinCandumpReader, StdinStreamReader

        if name in (None, "candump"):
            return StdinCandumpReader(wanted_ids=wanted_ids)
        if name == "stream":
            return StdinStreamReader()
        raise UsageError(f"standard input can be read as candump text or a stream, not {name}")
    if name is None:
        name = detect_format(path)
        if name == "candump" and b"\0" in _head(path):
            raise UsageError(f"{path} is not candump text (it holds binary data); give --format")
    if name == "candump":
        from analyzer.inputs.candump import CandumpReader

        return CandumpReader(path, wanted_ids=wanted_ids)
    if name == "pcap":
        from analyzer.inputs.pcap import PcapReader

        return PcapReader(path, port=port)
    if name == "stream":
        from analyzer.inputs.raw_stream import RawStreamReader

        return RawStreamReader(path)
    if name == "dataflash":
        from analyzer.inputs.dataflash import DataFlashReader

        return DataFlashReader(path)
    if name == "savvycan":
        from analyzer.inputs.savvycan import SavvyCanReader

        return SavvyCanReader(path)
    if name == "mcap":
        from analyzer.inputs.mcap import McapReader

        return McapReader(path, stored=stored)
    if name == "rosbag":
        from analyzer.inputs.rosbag import RosbagReader

        return RosbagReader(path)
    from analyzer.inputs.python_can import PythonCanReader

    return PythonCanReader(path, name)
