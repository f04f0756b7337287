"""Reading an MCAP file's messages record by record: unfinished, damaged and unindexed files."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from analyzer.mcapio.read.recover import Damage, Recovery, Scan, scan_records
from analyzer.mcapio.read.stored_message import (
    ChannelFilter,
    ChannelKind,
    MessageTally,
    RawMessage,
    ReadPosition,
    channel_kind,
)


def read_sequentially(
    path: str,
    size: int,
    wanted: ChannelFilter,
    tally: MessageTally | None,
    channels: dict[int, Any],
    report: Recovery,
    *,
    kinds_seen: dict[str, ChannelKind],
    damage: list[Damage],
    position: ReadPosition | None = None,
) -> Iterator[RawMessage | Damage]:
    """Messages of the wanted channels and the damaged parts, in file order.

    ``channels`` are the channel records known beforehand (from a summary); the others are
    learnt on the way. ``kinds_seen`` gets topic -> kind of every channel met;
    ``damage`` is the list of damaged parts the caller keeps (already yielded ones included);
    ``position`` follows the end of the last record read whole."""
    scan = Scan(size, report, channels=channels)
    roles: dict[int, tuple[str, str, bool]] = {}  # channel id -> topic, role, wanted
    with open(path, "rb") as f:
        for entry in scan_records(f, scan):
            if position is not None:
                position.bytes = report.good_bytes
            if isinstance(entry, Damage):
                yield entry
                continue
            known = roles.get(entry.channel_id)
            if known is None:
                channel = scan.channels.get(entry.channel_id)
                if channel is None:
                    report.unknown_channel += 1
                    continue
                topic = channel.topic
                schema = scan.schemas.get(channel.schema_id)
                kind = channel_kind(topic, dict(channel.metadata), schema, channel.message_encoding)
                kinds_seen[topic] = kind
                known = roles[entry.channel_id] = (topic, kind.role, wanted(topic, kind.role))
            report.messages += 1
            if tally is not None:
                tally(known[0], known[1], entry.log_time)
            if known[2]:
                yield RawMessage(known[0], known[1], entry.log_time, entry.data)
    if report.unknown_channel and not any("definition" in d.detail for d in damage):
        yield Damage(
            0,
            f"{report.unknown_channel} messages skipped: the record defining their "
            "channel was lost",
        )
