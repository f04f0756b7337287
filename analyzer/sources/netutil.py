"""Socket helpers shared by the TCP client and the TCP proxy sources."""

from __future__ import annotations

import contextlib
import socket


def enable_keepalive(
    sock: socket.socket,
    idle_s: int = 2,
    interval_s: int = 1,
    count: int = 3,
) -> None:
    """Detect a dead peer (pulled cable, powered-off IDU) within a few seconds, where supported."""
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
        if hasattr(socket, "TCP_KEEPIDLE"):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPIDLE, idle_s)
        if hasattr(socket, "TCP_KEEPINTVL"):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPINTVL, interval_s)
        if hasattr(socket, "TCP_KEEPCNT"):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPCNT, count)


def close_quietly(sock: socket.socket | None) -> None:
    """Shut a socket down both ways (unblocking a reader in another thread) and close it."""
    if sock is None:
        return
    with contextlib.suppress(OSError):
        sock.shutdown(socket.SHUT_RDWR)
    with contextlib.suppress(OSError):
        sock.close()


def address(host: str, port: int) -> str:
    """``host:port``, with IPv6 addresses in brackets."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def error_text(exc: BaseException) -> str:
    """A short reason for a socket error: the OS message without the errno prefix."""
    if isinstance(exc, TimeoutError | socket.timeout):
        return "timed out"
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror.lower() if exc.strerror[:1].isupper() else exc.strerror
    return str(exc) or exc.__class__.__name__
