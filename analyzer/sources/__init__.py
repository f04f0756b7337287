"""Live capture sources (CAN, TCP client, TCP proxy, serial, file replay) behind one spec."""

from __future__ import annotations

from analyzer.errors import UsageError
from analyzer.sources.base import Source, SourceItem, link_event
from analyzer.sources.spec import (
    SOURCE_FORMS,
    CanSpec,
    FileSpec,
    ProxySpec,
    SerialSpec,
    TcpSpec,
    parse_source,
)

__all__ = ["SOURCE_FORMS", "Source", "SourceItem", "link_event", "open_source", "parse_source"]


def open_source(url: str, *, replay_speed: float | None = None) -> Source:
    """Open the source a ``--source`` spec names (see SOURCE_FORMS).

    Raises UsageError for a bad spec, SourceError when the source cannot be opened.
    ``replay_speed`` applies to ``file:`` sources only (None: as fast as possible).
    """
    spec = parse_source(url)
    if replay_speed is not None and not isinstance(spec, FileSpec):
        raise UsageError("a replay speed applies to file: sources only")
    if isinstance(spec, CanSpec):
        from analyzer.sources.can_bus import CanSource

        return CanSource(spec)
    if isinstance(spec, TcpSpec):
        from analyzer.sources.tcp_client import TcpClientSource

        return TcpClientSource(spec.host, spec.port)
    if isinstance(spec, ProxySpec):
        from analyzer.sources.tcp_proxy import TcpProxySource

        return TcpProxySource(spec)
    if isinstance(spec, SerialSpec):
        from analyzer.sources.serial_port import SerialSource

        return SerialSource(spec)
    from analyzer.sources.file_replay import FileReplaySource

    return FileReplaySource(spec.path, replay_speed=replay_speed)
