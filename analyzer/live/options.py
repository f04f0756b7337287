"""The ``--foxglove [HOST:]PORT`` option of record, monitor and demo (light: no SDK import)."""

from __future__ import annotations

import argparse
from dataclasses import dataclass

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765
WILDCARD_HOSTS = frozenset({"0.0.0.0", "::", ""})


@dataclass(frozen=True, slots=True)
class ListenAddress:
    """Where the live server listens; port 0 lets the system pick a free one."""

    host: str
    port: int

    @property
    def everywhere(self) -> bool:
        return self.host in WILDCARD_HOSTS


def parse_listen_address(text: str) -> ListenAddress:
    """``8765``, ``127.0.0.1:8765``, ``0.0.0.0:8765`` or ``[::1]:8765`` -> ListenAddress."""
    text = text.strip()
    host, colon, port_text = text.rpartition(":")
    if not colon:
        host, port_text = DEFAULT_HOST, text
    host = host.strip()
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    elif ":" in host:
        raise argparse.ArgumentTypeError(
            f"{text!r}: write an IPv6 address in brackets, e.g. [::1]:{DEFAULT_PORT}"
        )
    if not host:
        raise argparse.ArgumentTypeError(f"{text!r}: no host before the ':' (e.g. 0.0.0.0:PORT)")
    try:
        port = int(port_text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not [HOST:]PORT (e.g. {DEFAULT_PORT} or 0.0.0.0:{DEFAULT_PORT})"
        ) from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"{text!r}: the port must be 0-65535")
    return ListenAddress(host, port)


def add_foxglove_options(parser: argparse.ArgumentParser) -> None:
    """``--foxglove [HOST:]PORT``: watch the decoded stream live in Foxglove."""
    parser.add_argument(
        "--foxglove",
        nargs="?",
        const=ListenAddress(DEFAULT_HOST, DEFAULT_PORT),
        type=parse_listen_address,
        metavar="[HOST:]PORT",
        help=f"also serve the decoded stream live to Foxglove (Open connection -> Foxglove "
        f"WebSocket, ws://HOST:PORT) with the same channels as a recording; --foxglove alone "
        f"is {DEFAULT_HOST}:{DEFAULT_PORT} (this machine only), 0.0.0.0:{DEFAULT_PORT} lets "
        "other machines connect, port 0 picks a free one",
    )


def listen_words(listen: ListenAddress, port: int) -> str:
    """Where the live server listens, in words: all interfaces is said so, with the address
    (``port`` is the one it got, when port 0 asked for a free one)."""
    where = f"[{listen.host}]:{port}" if ":" in listen.host else f"{listen.host}:{port}"
    if listen.everywhere:
        return (
            f"serving the live stream to Foxglove on all interfaces (ws://{where}): reachable "
            f"from other machines; --foxglove 127.0.0.1:{port} keeps it on this one"
        )
    return f"serving the live stream to Foxglove on ws://{where}"
