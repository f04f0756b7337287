"""Command-line options of every command that reads a capture file or recording."""

from __future__ import annotations

import argparse

from analyzer.errors import UsageError


def add_input_arguments(parser: argparse.ArgumentParser) -> None:
    """The input file, its format and the IDU's TCP port: decode, analyze, report."""
    from analyzer.inputs import FORMATS

    parser.add_argument("file", help="capture file or MCAP recording; '-' reads candump text")
    parser.add_argument(
        "--format",
        metavar="FORMAT",
        help="file format instead of guessing it: " + ", ".join(FORMATS),
    )
    add_port_argument(parser)


def add_port_argument(parser: argparse.ArgumentParser) -> None:
    """The IDU's TCP port in pcap captures (also for a command reading two inputs)."""
    parser.add_argument(
        "--port", type=int, default=2000, help="TCP port of the IDU in pcap captures (default 2000)"
    )


def check_port(port: int) -> None:
    """The IDU's TCP port of a pcap input (``--port``): UsageError unless 1..65535."""
    if not 0 < port < 65536:
        raise UsageError(f"--port must be 1..65535, not {port}")
