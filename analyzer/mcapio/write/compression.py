"""Chunk compression by name for the writer: zstd (as the mcap library's writer), lz4, none."""

from __future__ import annotations

from collections.abc import Callable

import lz4.frame
import zstandard

from analyzer.mcapio.write.options import COMPRESSIONS

ZSTD_LEVEL = 3  # what the mcap library's writer uses


def compressor(name: str) -> tuple[str, Callable[[bytes], bytes] | None]:
    """``zstd`` / ``lz4`` / ``none`` -> (the chunk's compression field, the function)."""
    if name == "zstd":
        return "zstd", zstandard.ZstdCompressor(level=ZSTD_LEVEL).compress
    if name == "lz4":
        return "lz4", lz4.frame.compress
    if name in ("none", ""):
        return "", None
    raise ValueError(f"unknown compression {name!r}; valid: {', '.join(COMPRESSIONS)}")
