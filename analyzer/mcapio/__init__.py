"""MCAP recordings: the writer sink, the (crash-tolerant) reader and the recording summary."""

from __future__ import annotations
