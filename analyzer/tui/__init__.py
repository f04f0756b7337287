"""The live terminal UI: gimbal and UAV state, command log, bus sniffer table, diagnostics."""

from __future__ import annotations
