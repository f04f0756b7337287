"""Well-formed ``candump -L`` lines found at C speed: one pattern that takes a whole block.

A busy bus log is mostly frames of other devices. Looking at each of those lines in
Python costs more than python-can's whole reader; one compiled pattern instead does the
work in C, in one pass over a block. Each of its matches takes a run of well-formed
classic frame lines of other IDs (checking each as strictly as the line parser does),
then one of: a wanted frame, with its parts as groups; any other line, whole, for the line
parser (damaged lines, remote, CAN FD and error frames, the screen layout, unusual ID
widths), which says what is wrong; or the end of the block. So the matches follow each
other from the block's start to its end, and the scan changes speed, never results
(``tests/test_inputs_candump_scan.py`` checks that). The wanted frames found become
CanFrames here (``can_frames``).
"""

from __future__ import annotations

import functools
import re
import sys
from binascii import unhexlify
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from itertools import repeat
from operator import itemgetter, truediv
from typing import cast

from analyzer.inputs.candump.line import DIRECTIONS
from analyzer.protocol.types import CanFrame

# Possessive quantifiers (Python 3.11 on) never give back what they took: no time is lost
# trying. A block is whole lines, and each part of the pattern ends where the next cannot
# begin, so on Python 3.10 the greedy ones find the same matches (the scan tests run on it).
_P = "+" if sys.version_info >= (3, 11) else ""
# A ``(seconds.fraction)`` stamp: at most 15 digits before the point (under 1e15 s, the
# line parser's limit).
_STAMP = f"\\([0-9]{{1,15}}{_P}\\.[0-9]+{_P}\\)"
_HEX = "[0-9A-Fa-f]"
# A channel name is what the line parser's ``split()`` leaves of it: no ASCII white space.
# The ID widths candump writes: 8 digits of an extended ID without the error flag (and
# below 0x20000000), or 3 digits of a standard one.
_ANY_ID = f"(?:[01]{_HEX}{{7}}|{_HEX}{{3}})"
# Classic CAN data: an even number of hex digits, at most 16 (tried longest first).
_DATA = "(?:" + "|".join(f"{_HEX}{{{n}}}" for n in range(16, 0, -2)) + "|)"

# (timestamp text, with 6 digits after the point; channel and ID text with the space
# between them; data in hex; direction letter or b""; other line): a wanted frame has the
# first three (the direction may be b""), a line for the line parser only the last (its
# line end included), the end of the block none. Channel and ID are one text: one object
# and one look-up a frame.
Found = tuple[bytes, bytes, bytes, bytes, bytes]
STAMP, WHERE, DATA, DIRECTION, OTHER = range(5)

# A file's block whose lines are at least this fraction of wanted frames is read as arrays
# (``columns``) and decoded in vectors; in a sparser one (a busy drone bus where a few
# frames in a hundred are the gimbal's) this scan skips the other frames at C speed and
# the few wanted become CanFrames. The last block decides for the next; the first 64 KiB
# of the first block for itself.
DENSE = 0.1
SAMPLE = 1 << 16


@dataclass(frozen=True)
class WantedIdPattern:
    """The pattern for one set of wanted IDs, as ``findall`` and as ``finditer``.

    ``findall(block)`` lists what the matches found, in order (a block is whole lines);
    ``finditer(block)`` gives the matches themselves, to know where each other line is.
    """

    findall: Callable[[bytes], list[Found]]
    finditer: Callable[[bytes], Iterator[re.Match[bytes]]]


def id_texts(ids: Iterable[int]) -> list[str]:
    """The ID texts of ``ids`` that the scan can meet: 8 digits, and 3 when the value fits."""
    texts = []
    for value in sorted(ids):
        if 0 <= value <= 0x1FFFFFFF:
            texts.append(f"{value:08X}")
            if value <= 0xFFF:
                texts.append(f"{value:03X}")
    return texts


def block_pattern(wanted_ids: frozenset[int] | None) -> str:
    """The pattern (see the module docstring) for this set of wanted IDs (None: all)."""
    if wanted_ids is None:
        wanted, other_id = _ANY_ID, "(?!)"  # every well-formed frame is wanted
    else:
        texts = id_texts(wanted_ids)
        wanted = f"(?i:{'|'.join(texts)})" if texts else "(?!)"
        other_id = f"(?!{wanted}#){_ANY_ID}"
    skipped = f"{_STAMP} \\S+{_P} {other_id}#{_DATA}(?: [RrTt])?\\n"
    # The wanted frame's stamp has 6 digits after the point, as candump writes it (for
    # ``stamp_times``); a wanted frame with another stamp goes to the line parser.
    frame = f"\\(([0-9]{{1,15}}{_P}\\.[0-9]{{6}})\\) (\\S+{_P} {wanted})#({_DATA})(?: ([RrTt]))?\\n"
    return f"(?:{skipped})*{_P}(?:{frame}|([^\\n]*{_P}\\n)|\\Z)"


def stamp_times(stamps: Iterable[bytes]) -> list[float]:
    """The times of ``seconds.micros`` stamp texts (6 digits after the point): exactly what
    ``float`` makes of them (both round the exact value to the nearest float; an integer
    divided by an integer is rounded once) at about half of ``float``'s cost, which is
    slow for the 16 digits candump writes."""
    return list(map(truediv, map(int, map(bytes.replace, stamps, _POINT, _NOTHING)), _MICRO))


_POINT, _NOTHING, _MICRO = repeat(b"."), repeat(b""), repeat(1_000_000)


@functools.lru_cache(maxsize=8)
def scanner(wanted_ids: frozenset[int] | None) -> WantedIdPattern:
    """The scan for this set of wanted IDs (None: every ID is wanted)."""
    pattern = re.compile(block_pattern(wanted_ids).encode())
    return WantedIdPattern(
        cast(Callable[[bytes], list[Found]], pattern.findall),
        pattern.finditer,
    )


Place = tuple[str, int, bool]  # channel name, ID value, extended
_STAMP_TEXT = itemgetter(STAMP)
_DIRECTION_OF = {b"": "", **DIRECTIONS}


def can_frames(
    found: list[Found],
    cached: Callable[[bytes], Place | None],
    place: Callable[[bytes], Place],
) -> list[CanFrame]:
    """The wanted frames the scan found, as CanFrames. ``cached`` gives the place of a
    ``channel ID`` text seen before (else None), ``place`` works it out."""
    direction_of = _DIRECTION_OF
    times = stamp_times(map(_STAMP_TEXT, found))
    return [
        CanFrame(
            time, p[1], unhexlify(data), p[2], p[0], False, False, False, direction_of[direction]
        )
        for (_, where, data, direction, _), time in zip(found, times, strict=True)
        for p in (cached(where) or place(where),)
    ]


def stamp_at(block: bytes, start: int) -> float:
    """The time of the scanned ``(seconds.fraction) ...`` line that starts at ``start``."""
    return float(block[start + 1 : block.index(b")", start)])
