"""Capture file readers: detection and `open_input` here, one module or package per format."""

from __future__ import annotations

from collections.abc import Iterable

from analyzer.errors import UsageError
from analyzer.inputs.base import InputItem, InputReader
from analyzer.inputs.detect import (
    EXTENSIONS,
    FORMATS,
    detect_format,
    normalise_format,
    read_head,
    sniff_format,
)
from analyzer.protocol.ids import TCP_PORT

__all__ = [
    "EXTENSIONS",
    "FORMATS",
    "InputItem",
    "InputReader",
    "detect_format",
    "normalise_format",
    "open_input",
    "sniff_format",
]


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
        if name == "candump" and b"\0" in read_head(path):
            raise UsageError(f"{path} is not candump text (it holds binary data); give --format")
    if name == "candump":
        from analyzer.inputs.candump.reader import CandumpReader

        return CandumpReader(path, wanted_ids=wanted_ids)
    if name == "pcap":
        from analyzer.inputs.pcap.reader import PcapReader

        return PcapReader(path, port=port)
    if name == "stream":
        from analyzer.inputs.raw_stream import RawStreamReader

        return RawStreamReader(path)
    if name == "dataflash":
        from analyzer.inputs.dataflash.reader import DataFlashReader

        return DataFlashReader(path)
    if name == "savvycan":
        from analyzer.inputs.savvycan import SavvyCanReader

        return SavvyCanReader(path)
    if name == "mcap":
        from analyzer.inputs.mcap import McapReader

        return McapReader(path, stored=stored)
    if name == "blf":
        from analyzer.inputs.blf.reader import BlfReader

        return BlfReader(path)
    if name == "rosbag":
        from analyzer.inputs.rosbag import RosbagReader

        return RosbagReader(path)
    from analyzer.inputs.python_can.reader import PythonCanReader

    return PythonCanReader(path, name)
