"""Bus sniffer table: one keyed row per CAN ID (or stream and direction), updated in place."""

from __future__ import annotations

from rich.text import Text
from textual.widgets import DataTable

from analyzer.tui.event_filter import EventFilter
from analyzer.tui.id_rows import IdRow
from analyzer.tui.state import MonitorState

MAX_DATA_BYTES = 8
COLUMNS = (("ID", "id", 11), ("Name", "name", 9), ("Count", "count", 9), ("Hz", "hz", 8))
DATA_WIDTH = 3 * MAX_DATA_BYTES - 1
# The panel's title by what the source delivers (MonitorState.items_counted): a TCP or
# UART source has a row per stream and direction, counting its chunks.
TITLES = {
    "frames": "CAN IDs",
    "chunks": "Streams: chunks by direction",
    "frames and chunks": "CAN IDs and streams (chunks)",
}

_CHANGED = "bold black on yellow"


def data_cell(row: IdRow, now: float) -> Text:
    """Hex bytes with those changed in the last second highlighted."""
    data = row.data[:MAX_DATA_BYTES]
    mask = row.changed_mask(now)
    text = Text(no_wrap=True)
    for i, byte in enumerate(data):
        if i:
            text.append(" ")
        text.append(f"{byte:02X}", _CHANGED if i < len(mask) and mask[i] else None)
    if len(row.data) > MAX_DATA_BYTES:
        text.append("…")
    return text


def row_cells(row: IdRow, now: float) -> tuple[object, ...]:
    """The cells of one table row; also the cache key that says whether to redraw it."""
    return (
        Text(row.key, style="" if row.protocol else "dim"),
        Text(row.label, style="bold" if row.protocol else "dim"),
        Text(f"{row.count:>8} "),
        Text(f"{row.meter.rate(now):7.1f} "),
        data_cell(row, now),
    )


def _row_signature(row: IdRow, now: float) -> tuple[object, ...]:
    return (row.count, round(row.meter.rate(now), 1), row.data, row.changed_mask(now))


class IdTable(DataTable[object]):
    """Rows keyed by ID; only rows whose numbers changed get their cells rewritten."""

    DEFAULT_CSS = """
    IdTable { border: round $primary; height: 1fr; }
    IdTable:focus { border: round $accent; }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id, cursor_type="row", cell_padding=0)
        self._shown: dict[str, tuple[object, ...]] = {}
        self._filter_text: str | None = None
        self._rows_added = -1
        self.updates = 0  # cells rewritten (tests and the benchmark look at this)

    def on_mount(self) -> None:
        self.border_title = TITLES["frames"]
        for label, key, width in COLUMNS:
            self.add_column(label, key=key, width=width)
        self.add_column("Data", key="data", width=DATA_WIDTH)

    def show(self, state: MonitorState, flt: EventFilter) -> None:
        now = state.now
        if flt.text != self._filter_text:
            self.clear()
            self._shown.clear()
            self._filter_text = flt.text
            self._rows_added = -1
        if state.rows_added != self._rows_added:
            added = False
            for row in state.rows.values():
                if row.key in self._shown or not flt.matches_row(row.can_id, row.label, row.key):
                    continue
                self.add_row(*row_cells(row, now), key=row.key)
                self._shown[row.key] = _row_signature(row, now)
                added = True
            if added:
                self.sort("id", key=lambda cell: str(cell))
            self._rows_added = state.rows_added
        # only rows on screen are rewritten; the others catch up when scrolled into view
        rows = {r.key: r for r in state.rows.values()} if self._shown else {}
        top = max(int(self.scroll_y), 0)
        for ordered in self.ordered_rows[top : top + self.size.height + 1]:
            key = str(ordered.key.value)
            current = rows.get(key)
            old = self._shown.get(key)
            if current is None or old is None:
                continue
            row = current
            signature = _row_signature(row, now)
            if signature == old:
                continue
            self._shown[key] = signature
            cells = row_cells(row, now)
            for (_, column, _), value in zip(COLUMNS[2:], cells[2:4], strict=True):
                self.update_cell(key, column, value)
            self.update_cell(key, "data", cells[4])
            self.updates += 1
        self.border_title = TITLES[state.items_counted]
        self.border_subtitle = f"{len(self._shown)} of {len(state.rows)}"
