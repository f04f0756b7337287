"""The tool's version and the protocol document it implements: what every output names."""

from __future__ import annotations

__version__ = "0.1.0"
PROTOCOL_NOTES = "docs/protocol-notes.md"  # the corrections to the vendor's document
PROTOCOL_DOCUMENT = (
    f"Gimbal Interface Definition and Protocols (vendor), with the corrections of {PROTOCOL_NOTES}"
)
