"""The messages of a chunk being built, reordered or split by the offsets of its message index."""

from __future__ import annotations

import bisect
import struct
from dataclasses import dataclass

_RECORD_HEAD = struct.Struct("<BQ")  # opcode, record length
_PAST_ANY_OFFSET = 1 << 64

# (log time, offset in the chunk, channel id) of one message
Placed = tuple[int, int, int]


@dataclass(slots=True)
class HoldBack:
    """A writer's hold-back: ``window`` (ns; 0 for none), the messages given to the writer
    up to the last flush, and the messages held out of a chunk while it is written (chunk,
    index, newest log time), kept should that write fail."""

    window: int
    given_at_flush: int = 0
    held_over: tuple[bytearray, dict[int, list[int]], int] | None = None


def messages_in_order(index: dict[int, list[int]]) -> list[Placed]:
    """The messages of a chunk's index (channel id -> [log time, offset, ...]) by log time,
    in the order they were added among equal times."""
    messages: list[Placed] = []
    for channel_id, pairs in index.items():
        messages.extend(
            zip(pairs[0::2], pairs[1::2], [channel_id] * (len(pairs) // 2), strict=True)
        )
    messages.sort()
    return messages


def count_until(messages: list[Placed], log_time: int) -> int:
    """How many of ``messages`` (in order) have a log time up to ``log_time``."""
    return bisect.bisect_right(messages, (log_time, _PAST_ANY_OFFSET, 0))


def rebuild(
    chunk: bytearray, head: bytes, messages: list[Placed]
) -> tuple[bytearray, dict[int, list[int]]]:
    """A chunk of ``head`` then the records of ``messages`` (taken from ``chunk``) in that
    order, with its message index."""
    rebuilt = bytearray(head)
    index: dict[int, list[int]] = {}
    for log_time, offset, channel_id in messages:
        _, length = _RECORD_HEAD.unpack_from(chunk, offset)
        index.setdefault(channel_id, []).extend((log_time, len(rebuilt)))
        rebuilt += chunk[offset : offset + 9 + length]
    return rebuilt, index
