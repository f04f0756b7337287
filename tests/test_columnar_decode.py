"""The columnar path gives exactly what reading and decoding frame by frame gives.

Every candump input is decoded twice: read as arrays and decoded in vectors (the
default), and read line by line and decoded one frame at a time (the reference). The
``decode --json`` lines, the counters, the reader's and the decoder's figures must be
the same, byte for byte: on the samples, the fault logs, a dense bus cut into blocks
that end inside lines and inside feedback messages, mixed line layouts, several
channels, CAN FD, remote and error frames, and logs damaged at random places.
"""

from __future__ import annotations

import json
import random
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.analysis.response import ResponseAnalyzer, Settings
from analyzer.fleet.column_sink import CollectedTables, ColumnSink
from analyzer.inputs.candump.columns import _all_digits, _all_hex, _decimal, _nibbles, _pack
from analyzer.inputs.candump.reader import CandumpReader
from analyzer.pipeline import Batch, Pipeline, run_items
from analyzer.protocol.crc import crc16
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.event_columns import EventColumns, _json_column
from analyzer.protocol.ids import PROTOCOL_IDS
from analyzer.protocol.vector_decode import crc16_rows
from benchmarks.decode_speed import dense_lines, traffic_lines
from tests.fault_logs import candump_lines

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = sorted((ROOT / "samples").glob("*.log"))


class Lines:
    """A sink that writes every event as its ``decode --json`` line."""

    keeps_items = False

    def __init__(self, columns: bool) -> None:
        self.takes_columns = columns
        self.lines: list[str] = []

    def handle(self, batch: Batch) -> None:
        for segment in batch.segments():
            if isinstance(segment, EventColumns):
                self.lines += segment.json_lines()
            else:
                self.lines += [json.dumps(e.to_dict(), default=str) for e in segment]

    def close(self) -> None:
        pass


def decoded(
    path: Path,
    *,
    columnar: bool,
    block_size: int = 1 << 20,
    raw: bool = False,
    columns: bool = True,
    analysis: bool = False,
) -> tuple[list[str], dict[str, Any]]:
    """``decode --json`` lines and every figure; with ``analysis`` the response analysis
    as a stage (its findings among the lines) and the fleet tables as ``table`` makes them
    (row groups of 500 rows)."""
    reader = CandumpReader(
        str(path), wanted_ids=None if raw else PROTOCOL_IDS, block_size=block_size, scan=columnar
    )
    sink = Lines(columns)
    kept = CollectedTables()
    fleet = ColumnSink(kept, "r", "h", group_rows=500)
    fleet.takes_columns = columns
    stages = [ResponseAnalyzer(Settings())] if analysis else []
    sinks: list[Any] = [sink, fleet] if analysis else [sink]
    pipeline = Pipeline(sinks, decoder=ProtocolDecoder(emit_other=raw), stages=stages)
    run_items(reader, pipeline, batch_items=2000)
    reader.close()
    figures = {
        "input": reader.stats,
        "decoder": pipeline.decoder.stats,  # type: ignore[attr-defined]
        "tally": pipeline.tally.figures(),
        "items": pipeline.tally.items(),
        "span": (pipeline.tally.first_time, pipeline.tally.last_time),
        "reader": (reader.first_time, reader.last_time, reader.time_base, reader.notes),
        "commands": list(pipeline.tally.commands),
    }
    if analysis:
        figures["tables"] = {name: t.to_pylist() for name, t in kept.tables().items()}
        figures["verdicts"] = (dict(fleet.verdicts), dict(fleet.health), fleet.rows)
    return sink.lines, figures


def assert_same(path: Path, **options: Any) -> list[str]:
    """Both paths on ``path``; returns the events' lines."""
    block = options.pop("block_size", 1 << 20)
    want = in_order(decoded(path, columnar=False, **options))
    got = in_order(decoded(path, columnar=True, block_size=block, **options))
    assert got[0] == want[0]
    assert got[1] == want[1]
    materialized = decoded(path, columnar=True, block_size=block, columns=False, **options)
    assert in_order(materialized) == want
    return want[0]


def in_order(result: tuple[list[str], dict[str, Any]]) -> tuple[list[str], dict[str, Any]]:
    """The lines with the analysis' findings after the rest: a stage adds its findings at
    the end of each batch, and the batches of blocks read as arrays end elsewhere than
    those of lines read one by one (the findings come in the same order all the same)."""
    lines, figures = result
    finding = '{"topic": "/analysis/response"'
    findings = [line for line in lines if line.startswith(finding)]
    return [line for line in lines if not line.startswith(finding)] + findings, figures


@pytest.mark.parametrize("raw", [False, True])
@pytest.mark.parametrize("path", SAMPLES, ids=lambda p: p.name)
def test_every_sample_decodes_the_same(path: Path, raw: bool) -> None:
    assert assert_same(path, raw=raw)


@pytest.mark.parametrize("path", SAMPLES, ids=lambda p: p.name)
def test_the_analysis_and_its_fleet_tables_are_the_same(path: Path) -> None:
    """What ``analyze`` and ``table`` make of a file: the analysis takes the blocks as
    columns (Events only of what it reads), the fleet tables their rows a column at a
    time, in frame order, row groups cut where they were."""
    lines = assert_same(path, analysis=True)
    assert any('"/analysis/response"' in line for line in lines)


def test_the_analysis_of_a_pilot_s_stick_on_a_dense_bus(tmp_path: Path) -> None:
    path = _dense(tmp_path, 40_000)
    lines = assert_same(path, analysis=True, block_size=65536)
    assert sum('"/analysis/response"' in line for line in lines) > 5


@pytest.mark.parametrize("seed", [22, 5, 77])
def test_the_fault_logs_decode_the_same(tmp_path: Path, seed: int) -> None:
    path = tmp_path / "faults.log"
    path.write_text("\n".join(candump_lines(seed)) + "\n", encoding="utf-8")
    for raw in (False, True):
        assert assert_same(path, raw=raw, block_size=3001)


def _dense(tmp_path: Path, frames: int, name: str = "dense.log", **kinds: Any) -> Path:
    path = tmp_path / name
    with path.open("w", encoding="utf-8") as f:
        for batch in dense_lines(frames, **kinds):
            f.write("\n".join(batch) + "\n")
    return path


@pytest.mark.parametrize("block_size", [517, 4096, 65536])
def test_blocks_that_end_inside_lines_and_feedback_messages(
    tmp_path: Path, block_size: int
) -> None:
    """Blocks of odd sizes cut lines in two, and the four segments of a feedback message
    fall into two blocks: the reassembler carries them over."""
    path = _dense(tmp_path, 6000)
    lines = assert_same(path, block_size=block_size)
    assert sum('"/gimbal/attitude"' in line for line in lines) == 6000 // 50


def test_a_busy_bus_of_many_line_widths_and_foreign_ids(tmp_path: Path) -> None:
    path = tmp_path / "busy.log"
    with path.open("w", encoding="utf-8") as f:
        for batch in traffic_lines(20_000):
            f.write("\n".join(batch) + "\n")
    assert_same(path, block_size=8192)
    assert_same(path, raw=True, block_size=8192)
    assert_same(_dense(tmp_path, 5000, "random.log", random_ids=True), raw=True)


MIXED = """\
(1715680800.000100) can0 00000F01#0F04640000000000
(1715680800.000200) can1 00000F01#0F04C80000000000 R
(1715680800.000300) vcan10 0000FF15#07108D1287356846 T
(1715680800.000400) can0 123#1122
(1715680800.000500) can0 00000F01#R
(1715680800.000600) can0 00000F01##10F04640000000000
(1715680800.000700) can0 20000004#0004000000000000
(1715680800.000800) can0 00000F01#0F04640000000000_9
  can0  00000F01   [8]  0F 04 64 00 00 00 00 00
(1715680800.000900)  can0  0000FF16   [8]  88 13 00 00 00 00 00 00
(1715680800.001) can0 00000F01#0F04640000000000
(1715680800.001100) can0 00000f01#0f04640000000000
(1715680800.001200) can0 F01#0F04640000000000
(1715680800.001300) can0 00000F01#0F04640000000000 X
(1715680800.001400) can0 00000F01#0F0464000000000
(1715680800.001500) can0 00000F01#0F9964000000000000
(1715680800.001600) can0 00000F01#0F04FFFF00000000
(1715680800.001700) can0 02008201#4241545445525920
(1715680800.001800) can0 02008202#3430000000000000
(1715680800.001900) c\xe4n 00000F01#0F04640000000000
(1715680800.002000) can0	00000F01#0F04640000000000
(1715680800.002100) can0 00000F01#
"""


def test_mixed_layouts_channels_fd_remote_and_error_frames(tmp_path: Path) -> None:
    """Screen lines, other stamps, lower-case hex, 3-digit IDs, remote, CAN FD, error
    frames, DLC suffixes, odd digits, a warning and unusual channel names between
    plain lines: each unusual line goes to the line parser in its place."""
    path = tmp_path / "mixed.log"
    path.write_bytes(MIXED.encode("latin-1") * 3)
    for block_size in (64, 300, 1 << 20):
        for raw in (False, True):
            assert assert_same(path, raw=raw, block_size=block_size)


DAMAGE = ["flip", "cut", "junk", "repeat", "swap", "drop", "fd", "remote", "error"]


@st.composite
def damaged(draw: st.DrawFn) -> tuple[list[str], int]:
    lines = [line for batch in dense_lines(600, seed=draw(st.integers(1, 5))) for line in batch]
    rng = random.Random(draw(st.integers(0, 2**32)))
    for _ in range(draw(st.integers(1, 12))):
        where = rng.randrange(len(lines))
        kind = rng.choice(DAMAGE)
        line = lines[where]
        if kind == "flip" and line:
            i = rng.randrange(len(line))
            lines[where] = line[:i] + chr(rng.randrange(32, 127)) + line[i + 1 :]
        elif kind == "cut":
            lines[where] = line[: rng.randrange(len(line) + 1)]
        elif kind == "junk":
            lines.insert(where, rng.choice(["garbage", "", "\tnote", "(1.0) x"]))
        elif kind == "repeat":
            lines.insert(where, line)
        elif kind == "swap" and where + 1 < len(lines):
            lines[where], lines[where + 1] = lines[where + 1], line
        elif kind == "drop":
            del lines[where]
        elif kind == "fd":
            lines.insert(where, line.replace("#", "##1", 1))
        elif kind == "remote":
            lines.insert(where, line.split("#")[0] + "#R")
        elif kind == "error":
            lines.insert(where, line.split(" ")[0] + " can0 20000004#0004000000000000")
    return lines, draw(st.sampled_from([97, 1000, 4096, 1 << 20]))


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(damaged())
def test_random_damage_anywhere_in_a_block(tmp_path: Path, case: tuple[list[str], int]) -> None:
    """Damage at the start, in the middle and at the end of blocks of any size."""
    lines, block_size = case
    path = tmp_path / "damaged.log"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert_same(path, block_size=block_size)


# -- the byte-eating helpers, against plain Python ------------------------------------------


def _word(text: bytes) -> np.ndarray:
    return np.frombuffer(text, "<u8").copy()


@given(st.binary(min_size=8, max_size=8))
def test_eight_byte_checks_and_numbers(text: bytes) -> None:
    w = _word(text)
    digits = all(48 <= b <= 57 for b in text)
    hexes = all(chr(b) in "0123456789abcdefABCDEF" for b in text)
    assert bool(_all_digits(w)[0]) == digits
    assert bool(_all_hex(w)[0]) == hexes
    if digits:
        assert int(_decimal(w)[0]) == int(text)
    if hexes:
        packed = int(_pack(_nibbles(w))[0])
        assert packed.to_bytes(4, "little") == bytes.fromhex(text.decode())


@given(st.lists(st.binary(min_size=32, max_size=32), min_size=1, max_size=20))
def test_crc_of_many_messages_at_once(messages: list[bytes]) -> None:
    array = np.frombuffer(b"".join(messages), np.uint8).reshape(-1, 32).astype(np.int64)
    sizes = np.array([25 + (m[0] & 4) for m in messages])
    got = crc16_rows(array, sizes).tolist()
    assert got == [crc16(m[:s]) for m, s in zip(messages, sizes.tolist(), strict=True)]


@given(
    st.one_of(
        st.lists(st.text(), min_size=1),
        st.lists(st.text(alphabet="0123456789ABCDEF "), min_size=1),
        st.lists(st.sampled_from(["full_lock", "35x zoom 2MP / 30x zoom 4K", 'a "b"']), min_size=1),
        st.lists(st.integers(-(2**40), 2**40), min_size=1),
        st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=1),
        st.lists(st.booleans(), min_size=1),
    )
)
def test_a_column_is_written_as_json_writes_each_value(values: list[Any]) -> None:
    assert _json_column(values) == [json.dumps(v) for v in values]
