"""gimbal-analyzer: decode, record and watch the gimbal CAN / TCP / UART protocol."""

from __future__ import annotations

__version__ = "0.1.0"
PROTOCOL_DOCUMENT = "Gimbal Interface Definition and Protocols (vendor), read with NOTES.md"
