"""gimbal-analyzer: decode, record and watch the gimbal CAN / TCP / UART protocol.

The Python API (docs/howto/python-api.md): ``encode``, ``can_message``, ``tcp_frame`` and
``status_message`` build what the gimbal is sent; ``Decoder`` (sans-IO) and ``Listener``
(python-can) decode what it says as ``Event``s; ``read``, ``analyze`` and ``Recording``
read capture files and recordings; ``COMMANDS`` is the command table.

>>> import analyzer
>>> analyzer.encode("look_down").hex(" ")
'0f 07 00 00 00 00 00 00'

Each name is imported on first use: ``import analyzer`` loads nothing else.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

# The version and the document's name live in analyzer.version, which every module that
# names them imports (never this root, which re-exports the API above them all).
from analyzer.version import PROTOCOL_DOCUMENT as PROTOCOL_DOCUMENT
from analyzer.version import PROTOCOL_NOTES as PROTOCOL_NOTES
from analyzer.version import __version__ as __version__

# Public name -> the module that defines it, imported when the name is first used.
_PUBLIC: dict[str, str] = {
    "COMMANDS": "analyzer.api.commands",
    "Decoder": "analyzer.api.decoding",
    "Event": "analyzer.protocol.types",
    "Finding": "analyzer.api.analysis",
    "Listener": "analyzer.api.listener",
    "Recording": "analyzer.api.recording",
    "analyze": "analyzer.api.analysis",
    "can_message": "analyzer.api.messages",
    "encode": "analyzer.api.encoding",
    "read": "analyzer.api.reading",
    "status_message": "analyzer.api.messages",
    "tcp_frame": "analyzer.api.encoding",
    "text_messages": "analyzer.api.messages",
}
__all__ = [
    "COMMANDS",
    "Decoder",
    "Event",
    "Finding",
    "Listener",
    "Recording",
    "analyze",
    "can_message",
    "encode",
    "read",
    "status_message",
    "tcp_frame",
    "text_messages",
]

if TYPE_CHECKING:
    from analyzer.api.analysis import Finding, analyze
    from analyzer.api.commands import COMMANDS
    from analyzer.api.decoding import Decoder
    from analyzer.api.encoding import encode, tcp_frame
    from analyzer.api.listener import Listener
    from analyzer.api.messages import can_message, status_message, text_messages
    from analyzer.api.reading import read
    from analyzer.api.recording import Recording
    from analyzer.protocol.types import Event
else:

    def __getattr__(name: str) -> Any:
        """A public name, imported on first use (PEP 562)."""
        module = _PUBLIC.get(name)
        if module is None:
            raise AttributeError(f"module 'analyzer' has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        globals()[name] = value
        return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
