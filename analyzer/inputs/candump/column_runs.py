"""A candump block read as arrays: runs of plain frame lines as FrameColumns, the rest in order.

The lines ``columns.read_lines`` took are counted as the scan counts the lines it takes
(lines, frames, frames of other IDs skipped, first and last time); every other line
goes to the line parser with its line number, between the runs, so that bad lines,
notes and unusual frames come out where they stand in the file.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from analyzer.inputs.base import InputItem
from analyzer.inputs.candump.columns import read_lines
from analyzer.inputs.textlines import MAX_LINE
from analyzer.protocol.frame_columns import FrameColumns

if TYPE_CHECKING:
    from analyzer.inputs.candump.linewise import CandumpLineParser


def parse_columns(parser: CandumpLineParser, block: bytes) -> list[InputItem]:
    """The items of ``block`` (whole lines), as the line parser gives them, in order."""
    table = read_lines(block, parser._channel)
    frames, fast = table.frames, table.fast
    n = fast.shape[0]
    wanted_ids = parser.wanted_ids
    wanted = None
    if wanted_ids is not None:
        wanted = fast & np.isin(frames.can_id, np.fromiter(wanted_ids, np.int64))
    out: list[InputItem] = []
    starts, ends = table.starts, table.ends
    previous = 0
    for line in [*np.flatnonzero(~fast).tolist(), n]:
        if line > previous:
            _run(parser, frames, previous, line, wanted, out)
        if line < n:
            parser.lines += 1
            start, end = int(starts[line]), int(ends[line])
            item = parser._slow_line(block[start : min(end, start + MAX_LINE + 1)], parser.lines)
            if item is not None:
                out.append(item)
        previous = line + 1
    return out


def _run(
    parser: CandumpLineParser,
    frames: FrameColumns,
    start: int,
    stop: int,
    wanted: np.ndarray | None,
    out: list[InputItem],
) -> None:
    """Lines ``start`` to ``stop`` (all read as frames): counted, the wanted ones handed on."""
    count = stop - start
    parser.lines += count
    parser.frames += count
    if wanted is None:
        rows: slice | np.ndarray = slice(start, stop)
        taken = count
    else:
        rows = start + np.flatnonzero(wanted[start:stop])
        taken = int(rows.shape[0])
    parser.frames_skipped += count - taken
    if parser.first_time is None:
        parser.first_time = float(frames.time[start])
    parser.last_time = float(frames.time[stop - 1])
    parser._after_error = False
    if taken:
        out.append(frames.take(rows))
