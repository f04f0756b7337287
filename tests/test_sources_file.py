"""File replay source: as fast as possible, at recorded speed, and the end of the file."""

from __future__ import annotations

import sys
import time
import types
from pathlib import Path
from typing import Any

import pytest

from analyzer.errors import UsageError
from analyzer.protocol.types import CanFrame, Event, StreamChunk
from analyzer.sources import open_source
from analyzer.sources.file_replay import FileReplaySource

T0 = 1_700_000_000.0


def recorded() -> list[Any]:
    return [
        CanFrame(T0, 0x00000F01, bytes([0x0F, 0x07, 0, 0, 0, 0, 0, 0])),
        StreamChunk(T0 + 0.1, b"\xeb\x90", "tcp", "idu_to_gs"),
        Event("/uav/text", T0 + 0.2, "can0", {"text": "hi"}),
        CanFrame(T0 + 0.3, 0x0000FF16, bytes(8)),
    ]


class FakeInput:
    def __init__(self, items: list[Any]) -> None:
        self.items = items
        self.closed = False

    def __iter__(self) -> Any:
        return iter(self.items)

    def close(self) -> None:
        self.closed = True


@pytest.fixture
def fake_inputs(monkeypatch: pytest.MonkeyPatch) -> list[FakeInput]:
    """Stands in for analyzer.inputs so these tests cover the replay logic only."""
    opened: list[FakeInput] = []

    def open_input(path: str) -> FakeInput:
        opened.append(FakeInput(recorded()))
        return opened[-1]

    module = types.ModuleType("analyzer.inputs")
    module.open_input = open_input  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "analyzer.inputs", module)
    return opened


def drain(source: Any) -> list[Any]:
    out: list[Any] = []
    while True:
        try:
            out.extend(source.read(0.05))
        except EOFError:
            return out


def test_fast_replay_yields_everything_then_ends(
    tmp_path: Path, fake_inputs: list[FakeInput]
) -> None:
    path = tmp_path / "flight.log"
    path.write_text("x", encoding="utf-8")
    source = open_source(f"file:{path}")
    started = time.monotonic()
    items = drain(source)
    assert time.monotonic() - started < 0.25
    assert items == recorded()  # unchanged, recorded timestamps kept
    with pytest.raises(EOFError):
        source.read(0.05)
    source.close()
    assert fake_inputs[0].closed
    assert source.description == f"file:{path}"


def test_recorded_speed_keeps_the_gaps(tmp_path: Path, fake_inputs: list[FakeInput]) -> None:
    path = tmp_path / "flight.log"
    path.write_text("x", encoding="utf-8")
    source = FileReplaySource(str(path), replay_speed=2.0)
    seen: list[tuple[float, Any]] = []
    started = time.monotonic()
    while True:
        try:
            batch = source.read(0.02)
        except EOFError:
            break
        seen.extend((time.monotonic() - started, item) for item in batch)
    assert [item for _, item in seen] == recorded()
    # 0.3 s of recording at twice the speed: the last item comes no earlier than 0.15 s
    assert seen[-1][0] >= 0.14
    assert seen[-1][0] < 2.0
    assert source.description.endswith(" at 2x")


def test_bad_replay_speed(tmp_path: Path) -> None:
    path = tmp_path / "f.log"
    path.write_text("x", encoding="utf-8")
    with pytest.raises(UsageError):
        open_source(f"file:{path}", replay_speed=0.0)


def test_replays_a_real_candump_file(tmp_path: Path) -> None:
    inputs = pytest.importorskip("analyzer.inputs")
    if not hasattr(inputs, "open_input"):
        pytest.skip("analyzer.inputs.open_input is not there yet")
    path = tmp_path / "flight.log"
    path.write_text(
        "(1700000000.000000) can0 00000F01#0F040CFE00000000\n"
        "(1700000000.100000) can0 0000FF16#F6C5000000000000\n",
        encoding="utf-8",
    )
    items = drain(open_source(f"file:{path}"))
    frames = [i for i in items if isinstance(i, CanFrame)]
    assert [f.can_id for f in frames] == [0x00000F01, 0x0000FF16]
    assert frames[0].time == pytest.approx(1_700_000_000.0)
