"""Sans-IO protocol core: bytes and frames with timestamps in, events out."""

from __future__ import annotations
