"""Which text-log lines python-can would skip without a word, and why they are damage.

python-can's ASC reader skips every line that does not look like a frame (a damaged
time included), and its TRC reader every line of a type it does not know (a damaged
type column included). A line that is a legitimate event of the format (a comment, a
trigger block, a status or statistics line, a TRC status or error counter) may be
skipped; any other line python-can would skip is damage, and is raised as
``SkippedLine`` so that it becomes a ``bad_line`` diagnostic with its number.
"""

from __future__ import annotations

import re
from collections.abc import Callable

# What python-can's ASCReader reads (can/io/asc.py, ASC_MESSAGE_REGEX, the trigger block
# and start-of-measurement lines); every other line it skips.
_ASC_READ = re.compile(
    r"\s*(\d+\.\d+\s+(\d+\s+(\w+\s+(Tx|Rx)|ErrorFrame)|CANFD)"
    r"|begin\s+triggerblock\s+\w+\s+\S)",
    re.ASCII | re.IGNORECASE,
)
# Lines of an ASC file that hold no frame: blank, comments, the header's keywords, the
# end of a trigger block, and timed events (``Start of measurement``, ``1 Statistic:``,
# ``CAN 1 Status:``, ``SV:``, ``log trigger event``, J1939...): a decimal time, perhaps a
# channel number, then a word that is no CAN identifier, with no Rx / Tx direction.
_ASC_NOT_A_FRAME = re.compile(
    r"\s*($|//|date\s|base\s|(no\s+)?internal\s+events\s+logged|(begin|end)\s+triggerblock"
    r"|\d+\.\d+\s+(\d+\s+)?(?![0-9a-f]+x?\b)[a-z](?!.*\b[RT]x\b))",
    re.ASCII | re.IGNORECASE,
)
_ASC_TIME = re.compile(r"\s*\d+\.\d+(\s|$)", re.ASCII)

# The TRC record types of PEAK's format: python-can reads the frames' types and skips
# the others (status, error counters, error frames, events; warnings in version 1.x).
_TRC_FRAMES_2 = frozenset({"DT", "FD", "FB", "FE", "BI", "RR"})
_TRC_OTHERS_2 = frozenset({"ST", "EC", "ER", "EV"})
_TRC_TYPES_1 = frozenset({"Rx", "Tx", "Warng", "Error"})
_TRC_TYPE_COLUMN_1 = {"1.1": 2, "1.3": 3}


class SkippedLine(ValueError):
    """A damaged line that python-can would have skipped without a word."""


def asc_problem(line: str) -> str | None:
    """Why python-can would silently skip this damaged ASC line (None: not damage)."""
    if _ASC_READ.match(line) or _ASC_NOT_A_FRAME.match(line):
        return None
    if not _ASC_TIME.match(line):
        first = line.split(None, 1)[0] if line.strip() else ""
        return f"its time {first[:20]!r} is not a decimal number"
    return "not a frame nor an event of the format"


def trc_checker(header: list[str]) -> Callable[[str], str | None]:
    """A check of a TRC file's lines for a damaged record type, from its header."""
    version = ""
    columns: list[str] = []
    for line in header:
        text = line.strip()
        if text.startswith(";$FILEVERSION="):
            version = text.split("=", 1)[1].strip()
        elif text.startswith(";$COLUMNS="):
            columns = text.split("=", 1)[1].strip().split(",")
    if version.startswith("2") and "T" in columns:
        where = columns.index("T")
        known = _TRC_FRAMES_2 | _TRC_OTHERS_2
    elif version in _TRC_TYPE_COLUMN_1:
        where = _TRC_TYPE_COLUMN_1[version]
        known = _TRC_TYPES_1
    else:  # version 1.0 has no type column: python-can says what it cannot parse
        return _no_problem

    def check(line: str) -> str | None:
        words = line.split(None, where + 1)
        if not words or words[0].startswith(";"):
            return None
        if len(words) <= where:
            return None  # too short: python-can's own parse error says so
        kind = words[where]
        if kind in known:
            return None
        return f"record type {kind[:20]!r} is none of PEAK's"

    return check


def _no_problem(line: str) -> str | None:
    return None
