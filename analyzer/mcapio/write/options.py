"""Recording options shared by the commands that write MCAP (light: no mcap import)."""

from __future__ import annotations

import argparse

COMPRESSIONS = ("zstd", "lz4", "none")
DEFAULT_COMPRESSION = "zstd"


def add_compression_argument(parser: argparse.ArgumentParser) -> None:
    """``--compression zstd|lz4|none`` for the commands that write a recording."""
    parser.add_argument(
        "--compression",
        choices=COMPRESSIONS,
        default=DEFAULT_COMPRESSION,
        help=f"compression of the recording's chunks (default {DEFAULT_COMPRESSION}, about 4x "
        "smaller than none; Foxglove and the mcap tools read all three)",
    )
