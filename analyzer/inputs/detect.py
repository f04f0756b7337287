"""Which format a capture file is in: from its name, else from its first bytes."""

from __future__ import annotations

import os
import re

from analyzer.errors import UsageError
from analyzer.inputs.base import open_binary
from analyzer.inputs.textlines import GZIP_MAGIC, TolerantGunzip

# The start of the header line SavvyCAN writes into its CSV files (lower case).
SAVVYCAN_HEADER_START = b"time stamp,id,extended,"


# --format values and what they read.
FORMATS: dict[str, str] = {
    "candump": "candump -L log or candump screen output (.log; '-' = standard input)",
    "asc": "Vector ASC (.asc) through python-can",
    "blf": "Vector BLF (.blf)",
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
            head = read_head(path)
        except UsageError:  # unreadable: the reader of the extension's format says why
            return EXTENSIONS[ext]
        return sniff_format(head) or EXTENSIONS[ext]
    if ext in EXTENSIONS:
        return EXTENSIONS[ext]
    found = sniff_format(read_head(path))
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
        from analyzer.inputs.dataflash.reader import looks_like_dataflash  # (not at each start-up)

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


def read_head(path: str) -> bytes:
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
