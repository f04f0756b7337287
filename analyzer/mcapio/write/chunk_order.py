"""The messages of a chunk being built, reordered or split by the offsets of its message index."""

from __future__ import annotations

import bisect
import struct
from dataclasses import dataclass

_RECORD_HEAD = struct.Struct("<BQ")  # opcode, record length
_PAST_ANY_OFFSET = 1 << 64

# (log time, offset in the chunk, channel id) of one message
Placed = tuple[int, int, int]
Index = dict[int, list[int]]  # channel id -> [log time, offset, log time, offset, ...]
# a chunk cut in two: the records up to a log time and their index, the rest and theirs,
# and whether the rest is in log-time order
Split = tuple[bytearray, Index, bytearray, Index, bool]
# where a chunk is cut: the offset, each channel's messages before it, the late ones after it
_Place = tuple[int, dict[int, int], list[int]]
# More late messages than this after the cut, and the chunk is rebuilt message by message.
MAX_LATE = 256


@dataclass(slots=True)
class HoldBack:
    """A writer's hold-back: ``window`` (ns; 0 for none), the messages given to the writer
    up to the last flush, and the messages held out of a chunk while it is written (chunk,
    index, newest log time, whether in log-time order), kept should that write fail."""

    window: int
    given_at_flush: int = 0
    held_over: tuple[bytearray, Index, int, bool] | None = None


def messages_in_order(index: Index) -> list[Placed]:
    """The messages of a chunk's index (channel id -> [log time, offset, ...]) by log time,
    in the order they were added among equal times."""
    messages: list[Placed] = []
    for channel_id, pairs in index.items():
        messages.extend(
            zip(pairs[0::2], pairs[1::2], [channel_id] * (len(pairs) // 2), strict=True)
        )
    messages.sort()
    return messages


def split_by_time(
    chunk: bytearray, head: bytes, index: Index, log_time: int, in_order: bool
) -> Split | None:
    """``chunk`` (its records ``head``, its messages in log-time order if ``in_order``) cut
    after ``log_time``: the head and the messages up to that time in log-time order, and
    the later ones; None when no message is later. Where the later messages begin at one
    place (the common case: a few late messages among them), the bytes are cut there;
    otherwise every message is copied to its place."""
    if not head:
        place = _one_cut(index, log_time, len(chunk))
        if place is not None:
            return _cut(chunk, index, place, in_order)
    messages = messages_in_order(index)
    split = bisect.bisect_right(messages, (log_time, _PAST_ANY_OFFSET, 0))
    if split == len(messages):
        return None
    if not split:
        return bytearray(), {}, chunk, index, in_order  # all of it is later
    held, held_index = rebuild(chunk, b"", messages[split:])
    closed, closed_index = rebuild(chunk, head, messages[:split])
    return closed, closed_index, held, held_index, True


def _one_cut(index: Index, log_time: int, end: int) -> _Place | None:
    """Where the messages later than ``log_time`` begin (``end`` if none is), how many of
    each channel's messages are not later, and the offsets of those that lie after that
    place all the same (a few late ones); None unless every channel's messages are in
    log-time order and such late ones are few."""
    cut = end
    counts: dict[int, int] = {}
    for channel_id, pairs in index.items():
        times = pairs[0::2]
        if times != sorted(times):
            return None
        count = counts[channel_id] = bisect.bisect_right(times, log_time)
        if count < len(times):
            cut = min(cut, pairs[2 * count + 1])
    late: list[int] = []
    for channel_id, count in counts.items():
        if count and index[channel_id][2 * count - 1] > cut:
            offsets = index[channel_id][1 : 2 * count : 2]
            late += offsets[bisect.bisect_right(offsets, cut) :]
            if len(late) > MAX_LATE:
                return None
    return cut, counts, sorted(late)


def _cut(chunk: bytearray, index: Index, place: _Place, in_order: bool) -> Split | None:
    """``split_by_time`` at the place ``_one_cut`` found: the bytes before it, sorted if
    need be with the late ones, and the bytes after it less the late ones."""
    cut, counts, late = place
    if cut == len(chunk):
        return None
    # the later part: the bytes from the cut on, less the late messages' records
    held = bytearray()
    shifts: list[tuple[int, int]] = []  # (offset, how far the bytes from there move back)
    start = cut
    for offset in late:
        shifts.append((start, start - len(held)))
        held += chunk[start:offset]
        _, length = _RECORD_HEAD.unpack_from(chunk, offset)
        start = offset + 9 + length
    shifts.append((start, start - len(held)))
    held += chunk[start:]
    closed_index: Index = {}
    held_index: Index = {}
    for channel_id, pairs in index.items():
        at = 2 * counts[channel_id]
        if at:
            closed_index[channel_id] = pairs[:at]
        if at < len(pairs):
            rest = pairs[at:]
            rest[1::2] = _moved(rest[1::2], shifts)
            held_index[channel_id] = rest
    closed = chunk[:cut]
    if not in_order and closed_index:  # the few late ones sorted into place
        closed, closed_index = rebuild(chunk, b"", messages_in_order(closed_index))
    return closed, closed_index, held, held_index, in_order


def _moved(offsets: list[int], shifts: list[tuple[int, int]]) -> list[int]:
    """``offsets`` (in increasing order) moved back as ``shifts`` say for where they lie."""
    if len(shifts) == 1:
        back = shifts[0][1]
        return [offset - back for offset in offsets]
    out: list[int] = []
    for n, (_, back) in enumerate(shifts):
        end = shifts[n + 1][0] if n + 1 < len(shifts) else None
        upto = len(offsets) if end is None else bisect.bisect_left(offsets, end)
        out += [offset - back for offset in offsets[len(out) : upto]]
    return out


def rebuild(chunk: bytearray, head: bytes, messages: list[Placed]) -> tuple[bytearray, Index]:
    """A chunk of ``head`` then the records of ``messages`` (taken from ``chunk``) in that
    order, with its message index."""
    rebuilt = bytearray(head)
    index: Index = {}
    for log_time, offset, channel_id in messages:
        _, length = _RECORD_HEAD.unpack_from(chunk, offset)
        index.setdefault(channel_id, []).extend((log_time, len(rebuilt)))
        rebuilt += chunk[offset : offset + 9 + length]
    return rebuilt, index
