"""candump -L text as candump writes it and as damage and other tools leave it, and a
parser fed it in blocks: the texts of the property tests of the readers."""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

from analyzer.inputs.candump.reader import CandumpParser
from analyzer.protocol.ids import PROTOCOL_IDS
from analyzer.protocol.types import Event

WANTED = [f"{i:08X}".encode() for i in sorted(PROTOCOL_IDS)] + [b"F01", b"00000f01"]
FOREIGN = [b"18F00000", b"0CF00400", b"123", b"7E8", b"1FFFFFFF", b"00000F02", b"F02"]
ODD_IDS = [b"20000080", b"3FFFFFFF", b"FFFFFFFF", b"12345", b"1", b"", b"0000XF01", b"000000F01"]


def _stamp(draw: st.DrawFn) -> bytes:
    kind = draw(st.sampled_from(["plain", "plain", "plain", "short", "long", "odd"]))
    if kind == "plain":
        return b"(%d.%06d)" % (
            draw(st.integers(1_700_000_000, 1_700_000_100)),
            draw(st.integers(0, 999_999)),
        )
    if kind == "short":
        return b"(%d.%d)" % (draw(st.integers(0, 9)), draw(st.integers(0, 9)))
    if kind == "long":
        return b"(" + b"9" * draw(st.integers(14, 17)) + b".5)"
    return draw(
        st.sampled_from([b"(.5)", b"(5.)", b"(1.2.3)", b"(1e3)", b"1.0)", b"(1.0", b"(-1.0)"])
    )


@st.composite
def lines(draw: st.DrawFn) -> bytes:
    """A line as candump writes it, or as damage, other layouts and other tools leave it."""
    shape = draw(st.sampled_from(["frame"] * 6 + ["screen", "blank", "junk", "note", "bytes"]))
    if shape == "blank":
        return draw(st.sampled_from([b"", b"   ", b"\t"]))
    if shape == "junk":
        return draw(
            st.sampled_from([b"# comment", b"***BUSMASTER", b"date Mon", b"(1.0)", b"garbage"])
        )
    if shape == "note":
        return b"\tbus-error{{}}{{}}"
    if shape == "bytes":
        return draw(st.binary(max_size=40)).replace(b"\n", b"")
    if shape == "screen":
        return draw(
            st.sampled_from(
                [
                    b"  can0  00000F01   [8]  0F 07 00 00 00 00 00 00",
                    b"(0.000100)  can0  18F00000   [2]  11 22",
                    b"(1436509052.249713)  can0  123   [0]  remote request",
                ]
            )
        )
    stamp = _stamp(draw)
    channel = draw(st.sampled_from([b"can0", b"vcan1", b"c(1.0)", b"a#b", b"can0\r", b""]))
    can_id = draw(st.sampled_from(WANTED + FOREIGN + ODD_IDS))
    data = draw(
        st.sampled_from(
            [
                b"0F0700000000C800",
                b"EB900C0000000000",
                b"",
                b"AB",
                b"abcd",
                b"ABC",
                b"0011223344556677",
                b"001122334455667788",
                b"0G",
                b"R",
                b"R5",
                b"#1AABB",
                b"1122334455667788_C",
            ]
        )
    )
    suffix = draw(st.sampled_from([b"", b"", b"", b" R", b" T", b" t", b" X", b"  R", b" "]))
    sep = draw(st.sampled_from([b" ", b" ", b" ", b"  ", b"\t"]))
    return stamp + sep + channel + b" " + can_id + b"#" + data + suffix


def parse(
    text: bytes, cuts: list[int], *, dense: bool | None = None, **kwargs: Any
) -> tuple[list[Any], CandumpParser]:
    """Parse ``text`` (whole lines) in blocks cut at the given line ends; ``dense`` (a
    columnar parser): every block as arrays, or none, whatever the last one held."""
    parser = CandumpParser("test.log", **kwargs)
    ends = [i + 1 for i, c in enumerate(text) if c == 0x0A]
    chosen = sorted({ends[c % len(ends)] for c in cuts}) if ends else []
    items: list[Any] = []
    start = 0
    for end in [*chosen, len(text)]:
        if dense is not None:
            parser.dense = dense
        if end > start:
            items += parser.parse_block(text[start:end])
        start = end
    if dense is not None:
        parser.dense = dense
    items += parser.finish()
    return items, parser


def summary(items: list[Any], parser: CandumpParser) -> tuple[Any, ...]:
    shown = [(i.topic, i.time, dict(i.fields)) if isinstance(i, Event) else i for i in items]
    return (
        shown,
        parser.stats,
        parser.first_time,
        parser.last_time,
        parser.base_of_times(),
        parser.notes,
    )


# Any text of such lines, where a reader's blocks may end (line ends, by index), and
# the IDs it is asked for.
TEXTS = st.lists(lines(), max_size=60).map(lambda text: b"".join(line + b"\n" for line in text))
CUTS = st.lists(st.integers(0, 10_000), max_size=4)
WANTED_SETS = st.sampled_from([PROTOCOL_IDS, None, frozenset({0x123, 0x18F00000})])
