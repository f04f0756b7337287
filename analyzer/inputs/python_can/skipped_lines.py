"""Which text-log lines python-can would skip without a word, and why they are damage.

python-can's ASC reader skips every line that does not look like a frame (a damaged
time included), and its TRC reader every line of a type it does not know (a damaged
type column included) or that starts with ``;``. A line that is a legitimate event of
the format (a comment, a trigger block, a status or statistics line, a TRC status or
error counter) may be skipped; any other line python-can would skip is damage, and is raised as
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
# Lines of an ASC file that hold no frame and no time: blank, comments, the header's
# keywords, the trigger block's lines.
_ASC_UNTIMED = re.compile(
    r"\s*($|//|date\s|base\s|(no\s+)?internal\s+events\s+logged|(begin|end)\s+triggerblock)",
    re.ASCII | re.IGNORECASE,
)
_DECIMAL = re.compile(r"\d+\.\d+", re.ASCII)
_CAN_ID = re.compile(r"[0-9a-f]+x?", re.ASCII | re.IGNORECASE)
# The name of an event (``Statistic:``, ``Status:...``, ``J1939TP``); Rx / Tx there is a
# frame's line that lost its ID.
_EVENT_NAME = re.compile(r"(?![RT]x$)[a-z]\w*(:.*)?", re.ASCII | re.IGNORECASE)
# A frame's line with a damaged channel or ID: ``time ? ? Rx``, ``time ? ErrorFrame``
# (CAN FD: ``time CANFD CHANNEL Rx``).
_FRAME_SHAPE = re.compile(r"\s*\S+\s+\S+\s+(\S+\s+(Rx|Tx)|ErrorFrame)(\s|$)", re.ASCII)

# The TRC record types of PEAK's format: python-can reads the frames' types and skips
# the others (status, error counters, error frames, events; warnings in version 1.x).
_TRC_FRAMES_2 = frozenset({"DT", "FD", "FB", "FE", "BI", "RR"})
_TRC_OTHERS_2 = frozenset({"ST", "EC", "ER", "EV"})
_TRC_TYPES_1 = frozenset({"Rx", "Tx", "Warng", "Error"})
_TRC_TYPE_COLUMN_1 = {"1.1": 2, "1.3": 3}
_DIRECTIONS = frozenset({"Rx", "Tx"})


class SkippedLine(ValueError):
    """A damaged line that python-can would have skipped without a word."""


def asc_problem(line: str) -> str | None:
    """Why python-can would silently skip this damaged ASC line (None: not damage).

    A timed line that is no frame is an event of the format when the word after its time
    (and channel) is a name: ``Start of measurement``, ``1 Statistic:``, ``CAN 1
    Status:``, ``SV:``, ``1 J1939TP``...; a frame's line with a damaged field is not.
    """
    if _ASC_READ.match(line) or _ASC_UNTIMED.match(line):
        return None
    words = line.split(None, 3)
    if not words:  # separators python-can's patterns do not take for blanks (\x1c-\x1f)
        return "a line of control characters"
    if not _DECIMAL.fullmatch(words[0]):
        return f"its time {words[0][:20]!r} is not a decimal number"
    if _FRAME_SHAPE.match(line):
        return "a frame's channel or ID is damaged"
    rest = words[2:] if len(words) > 2 and words[1].isdigit() else words[1:]
    if rest and _EVENT_NAME.fullmatch(rest[0]) and not _CAN_ID.fullmatch(rest[0]):
        return None  # an event python-can does not read
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
        known, frames = _TRC_FRAMES_2 | _TRC_OTHERS_2, _TRC_FRAMES_2
    elif version in _TRC_TYPE_COLUMN_1:
        where = _TRC_TYPE_COLUMN_1[version]
        known, frames = _TRC_TYPES_1, _DIRECTIONS
    else:  # version 1.0 has no type column: python-can says what it cannot parse
        return _no_problem

    def check(line: str) -> str | None:
        words = line.split(None, where + 1)
        if not words:
            return None
        if words[0].startswith(";"):  # a comment; a frame's line that became one is not
            tokens = set(line.replace(";", " ").split())
            if tokens & frames and tokens & _DIRECTIONS and len(tokens) > where + 2:
                return "a frame's line made a comment by a ';'"
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
