"""Lay text cells into lines of a given width so that no value is ever cut off.

Panels describe their content as cells (a label with its value, an age, a note); these
helpers place the cells side by side while they fit and move the rest to the next line,
so a narrow terminal gets more lines instead of values ending in an ellipsis.
"""

from __future__ import annotations

from collections.abc import Sequence

from rich.text import Text


def fold(cell: Text, width: int) -> list[Text]:
    """A cell cut into pieces of at most ``width`` cells (only when it is wider than a line)."""
    width = max(width, 1)
    pieces: list[Text] = []
    rest = cell
    while rest.cell_len > width:
        # break at the last space that keeps the piece within the width, else mid-word
        cut = rest.plain.rfind(" ", 1, width + 1)
        if cut <= 0:
            cut = width
        head, tail = rest.divide([cut])
        pieces.append(head)
        spaces = len(tail.plain) - len(tail.plain.lstrip(" "))
        rest = tail[spaces:] if spaces else tail
    if rest.plain or not pieces:
        pieces.append(rest)
    return pieces


def pack(
    cells: Sequence[Text],
    width: int,
    *,
    gap: int = 2,
    indent: int = 0,
    joiner: Text | None = None,
) -> list[Text]:
    """Cells left to right, a new line (indented by ``indent``) when the next one would not fit.

    Cells on one line are separated by ``gap`` spaces, or by ``joiner`` when given.
    """
    width = max(width, 1)
    joiner = joiner if joiner is not None else Text(" " * gap)
    gap = joiner.cell_len
    lines: list[Text] = []
    line: Text | None = None
    for cell in cells:
        if not cell.plain:
            continue
        if line is not None and line.cell_len + gap + cell.cell_len <= width:
            line.append_text(joiner)
            line.append_text(cell)
            continue
        if line is not None:
            lines.append(line)
        start = 0 if line is None else indent
        room = width - start
        pieces = fold(cell, room)
        for piece in pieces[:-1]:
            lines.append(Text(" " * start) + piece)
            start = indent
        line = Text(" " * start) + pieces[-1]
    if line is not None:
        lines.append(line)
    return lines or [Text()]


def grid(cells: Sequence[Text], width: int, *, gap: int = 2, max_columns: int = 0) -> list[Text]:
    """Cells in aligned columns, as many as fit (at least one; wide cells fold)."""
    if not cells:
        return []
    cell_width = max(c.cell_len for c in cells)
    columns = max(1, (width + gap) // (cell_width + gap))
    if max_columns:
        columns = min(columns, max_columns)
    if columns == 1:
        return [piece for c in cells for piece in fold(c, width)]
    lines: list[Text] = []
    for start in range(0, len(cells), columns):
        row = Text()
        for i, cell in enumerate(cells[start : start + columns]):
            if i:
                row.append(" " * gap)
            row.append_text(cell)
            if start + i + 1 < min(start + columns, len(cells)):
                row.append(" " * (cell_width - cell.cell_len))
        lines.append(row)
    return lines


def join_lines(lines: Sequence[Text]) -> Text:
    """One Text of ``lines``, never wrapped or cut again by the widget."""
    text = Text("\n").join(lines)
    text.no_wrap = True
    text.overflow = "crop"
    return text
