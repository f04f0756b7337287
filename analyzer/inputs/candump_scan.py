"""Well-formed ``candump -L`` lines found at C speed: runs of frames, and the wanted ones.

A busy bus log is mostly frames of other devices. Looking at each of those lines in
Python costs more than python-can's whole reader; two compiled patterns instead do the
work in C: one finds how far a run of well-formed classic frame lines goes (checking each
as strictly as the line parser does), the other picks the wanted frames out of such a
run with their parts as groups. Whatever the first does not take (damaged lines, remote,
CAN FD and error frames, the screen layout, unusual ID widths) is left to the line
parser, which says what is wrong; so the scan changes speed, never results
(``tests/test_inputs_candump_scan.py`` checks that).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import cast

# A ``(seconds.fraction)`` stamp: at most 15 digits before the point (under 1e15 s, the
# line parser's limit).
_STAMP = r"\([0-9]{1,15}+\.[0-9]++\)"
_HEX = "[0-9A-Fa-f]"
# A channel name is what the line parser's ``split()`` leaves of it: no ASCII white space.
# The ID widths candump writes: 8 digits of an extended ID without the error flag (and
# below 0x20000000), or 3 digits of a standard one.
_ANY_ID = f"(?:[01]{_HEX}{{7}}|{_HEX}{{3}})"
# Classic CAN data: an even number of hex digits, at most 16 (tried longest first).
_DATA = "(?:" + "|".join(f"{_HEX}{{{n}}}" for n in range(16, 0, -2)) + "|)"
_RUN = f"(?:{_STAMP} \\S++ {_ANY_ID}#{_DATA}(?: [RrTt])?\\n)*+"

# (timestamp text, channel, ID text, data in hex, direction letter or b"")
Found = tuple[bytes, bytes, bytes, bytes, bytes]


@dataclass(frozen=True)
class Scan:
    """The two patterns for one set of wanted IDs.

    ``run(block, pos).end()`` is the end of the run of well-formed lines from ``pos``
    (``pos`` itself when the line there is the line parser's); ``wanted(block, pos,
    end)`` lists the wanted frames of such a run, in order.
    """

    run: Callable[[bytes, int], re.Match[bytes]]
    wanted: Callable[[bytes, int, int], list[Found]]


def id_texts(ids: Iterable[int]) -> list[str]:
    """The ID texts of ``ids`` that the scan can meet: 8 digits, and 3 when the value fits."""
    texts = []
    for value in sorted(ids):
        if 0 <= value <= 0x1FFFFFFF:
            texts.append(f"{value:08X}")
            if value <= 0xFFF:
                texts.append(f"{value:03X}")
    return texts


@functools.lru_cache(maxsize=8)
def scanner(wanted_ids: frozenset[int] | None) -> Scan:
    """The scan for this set of wanted IDs (None: every ID is wanted)."""
    if wanted_ids is None:
        wanted = _ANY_ID
    else:
        texts = id_texts(wanted_ids)
        wanted = f"(?i:{'|'.join(texts)})" if texts else "(?!)"
    # Within a run every line is known to be well-formed: the parts need no more checks,
    # and a match can only start at a line's start (nothing else in a line can begin
    # ``(digits) name ID#``).
    frame = f"\\(([0-9.]++)\\) (\\S++) ({wanted})#({_HEX}*+)(?: ([RrTt]))?\\n"
    return Scan(
        cast(Callable[[bytes, int], "re.Match[bytes]"], re.compile(_RUN.encode()).match),
        cast(Callable[[bytes, int, int], list[Found]], re.compile(frame.encode()).findall),
    )
