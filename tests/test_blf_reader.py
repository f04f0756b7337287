"""Our BLF reader against python-can's, and on what python-can cannot read.

The reference is python-can's ``BLFReader`` (what decoded BLF before): on every file
python-can reads, ours gives the same frames, and decoding them gives the same events,
byte for byte, whether its CAN messages came as columns or one by one. Then the files
python-can gets wrong: object header version 3 (CANoe 15's default), an object whose
size is 0 (python-can reads it for ever), objects of other kinds, objects outside
containers, stored containers, damage anywhere; each is read through, in bounded time
and memory, and every object skipped is said.
"""

from __future__ import annotations

import json
import threading
from pathlib import Path
from typing import Any

import can
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.errors import UsageError
from analyzer.inputs import open_input
from analyzer.inputs.blf.reader import BlfReader
from analyzer.inputs.candump.reader import CandumpReader
from analyzer.pipeline import Pipeline, run_items
from analyzer.protocol.can_message import frame_from_message
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.types import BAD_FRAME, TOPIC_DIAGNOSTICS, CanFrame, Event
from tests import blf_files as blf
from tests.fault_logs import candump_lines
from tests.test_columnar_decode import Lines

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = sorted((ROOT / "samples").glob("*.log"))


def python_can_frames(path: Path) -> list[CanFrame]:
    with can.BLFReader(str(path)) as reader:
        return [frame_from_message(m) for m in reader]


def our_items(path: Path) -> list[Any]:
    reader = open_input(str(path))
    assert isinstance(reader, BlfReader)
    with reader:
        return list(reader)


def decoded(items: Any, columns: bool = True) -> tuple[list[str], dict[str, Any]]:
    """``decode --json`` lines and the counters of ``items`` (a reader or frames)."""
    sink = Lines(columns)
    pipeline = Pipeline([sink], decoder=ProtocolDecoder(emit_other=True))
    run_items(items, pipeline, batch_items=2000)
    tally = pipeline.tally
    return sink.lines, {"figures": tally.figures(), "items": tally.items()}


def messages_of(path: Path) -> list[can.Message]:
    """A candump log's frames as python-can messages (the frames a bus logger records)."""
    reader = CandumpReader(str(path), scan=False)
    out = []
    for frame in reader:
        if not isinstance(frame, CanFrame):
            continue
        out.append(
            can.Message(
                timestamp=frame.time,
                arbitration_id=frame.can_id,
                is_extended_id=frame.extended,
                is_remote_frame=frame.is_remote,
                is_error_frame=frame.is_error,
                is_fd=frame.is_fd,
                is_rx=frame.direction != "tx",
                dlc=frame.dlc,
                data=frame.data,
                channel=0 if frame.channel in ("can0", "") else 1,
            )
        )
    return out


def write_blf(path: Path, messages: list[can.Message], **options: Any) -> Path:
    with can.BLFWriter(str(path), **options) as writer:
        for message in messages:
            writer.on_message_received(message)
    return path


def assert_as_python_can(path: Path) -> list[str]:
    """Our reader and python-can's give the same frames; decoded, the same events (our
    columns and python-can's frames one by one)."""
    items = our_items(path)
    assert all(isinstance(i, CanFrame) for i in items), [i for i in items if isinstance(i, Event)]
    reference = python_can_frames(path)
    assert items == reference
    with BlfReader(str(path)) as reader:
        got = decoded(reader)
    with BlfReader(str(path)) as reader:
        assert decoded(reader, columns=False) == got
    assert got == decoded(reference)
    return got[0]


@pytest.mark.parametrize("path", SAMPLES, ids=lambda p: p.name)
def test_every_sample_as_python_can_writes_it(tmp_path: Path, path: Path) -> None:
    assert assert_as_python_can(write_blf(tmp_path / "x.blf", messages_of(path)))


@pytest.mark.parametrize("options", [{}, {"compression_level": 0}, {"max_container_size": 999}])
def test_the_fault_logs_in_every_container_layout(tmp_path: Path, options: dict[str, Any]) -> None:
    """Zlib containers, stored ones, and small containers that objects span."""
    log = tmp_path / "faults.log"
    log.write_text("\n".join(candump_lines(5)) + "\n", encoding="utf-8")
    lines = assert_as_python_can(write_blf(tmp_path / "x.blf", messages_of(log), **options))
    assert any('"/diagnostics"' in line for line in lines)


def test_error_remote_and_fd_frames_as_python_can_reads_them(tmp_path: Path) -> None:
    messages = [
        can.Message(timestamp=1e9, arbitration_id=0xF01, data=b"\x0f\x04" + bytes(6)),
        can.Message(timestamp=1e9 + 0.1, arbitration_id=0xF01, is_remote_frame=True, dlc=8),
        can.Message(
            timestamp=1e9 + 0.2,
            arbitration_id=0x20000004,
            is_error_frame=True,
            data=bytes([0, 4, 0, 0, 0, 0, 0, 0]),
        ),
        can.Message(timestamp=1e9 + 0.3, arbitration_id=0xF01, is_fd=True, data=bytes(12)),
        can.Message(
            timestamp=1e9 + 0.4,
            arbitration_id=0x7E8,
            is_extended_id=False,
            data=b"\x01",
            is_rx=False,
            channel=3,
        ),
    ]
    lines = assert_as_python_can(write_blf(tmp_path / "x.blf", messages))
    assert [json.loads(line)["topic"] for line in lines][:2] == [
        "/gimbal/command",
        TOPIC_DIAGNOSTICS,
    ]


def test_a_dense_log_comes_as_columns(tmp_path: Path) -> None:
    from benchmarks.decode_speed import write_log

    log = tmp_path / "dense.log"
    write_log(log, 20_000, "dense")
    path = write_blf(tmp_path / "dense.blf", messages_of(log))
    with BlfReader(str(path)) as reader:
        items = [i for batch in reader.batches(2000) for i in batch]
    assert items and all(isinstance(i, FrameColumns) for i in items)
    assert sum(map(len, items)) == 20_000
    assert_as_python_can(path)


# -- what python-can does not read ----------------------------------------------------------


def frames_of(version: int, kind: int = blf.CAN_MESSAGE) -> list[bytes]:
    """A feedback message, a command and a GPS frame, each object in header ``version``."""
    second = kind == blf.CAN_MESSAGE2
    bodies = [
        blf.can_message(0x030F0001, bytes.fromhex(hexa), second=second)
        for hexa in ("EB900C0000000000", "0000000021FE0F01", "01000333F3C83200", "00F1E30000000000")
    ]
    bodies += [
        blf.can_message(0xF01, bytes.fromhex("0F04E80300000000"), second=second),
        blf.can_message(0xFF15, bytes.fromhex("07108D1287356846"), second=second, sent=True),
    ]
    return [
        blf.blf_object(kind, body, stamp=1_000_000 * i, version=version)
        for i, body in enumerate(bodies)
    ]


@pytest.mark.parametrize("containers", ["zlib", "stored", "none"])
def test_header_versions_1_2_and_3_read_alike(tmp_path: Path, containers: str) -> None:
    """python-can reads versions 1 and 2 and skips 3 (its issue #1950, CANoe 15): ours
    reads all three as python-can reads version 1, in every kind of container."""
    paths = {}
    for version in (1, 2, 3):
        paths[version] = tmp_path / f"v{version}.blf"
        paths[version].write_bytes(blf.blf_file(frames_of(version), containers=containers))
    ones = our_items(paths[1])
    assert len(ones) == 6 and ones[0].time == blf.START_TIME
    assert our_items(paths[2]) == ones == our_items(paths[3])
    if containers != "none":  # python-can reads containers only
        assert python_can_frames(paths[1]) == ones == python_can_frames(paths[2])
        assert python_can_frames(paths[3]) == []
    message2 = tmp_path / "message2.blf"
    message2.write_bytes(blf.blf_file(frames_of(3, blf.CAN_MESSAGE2), containers=containers))
    assert our_items(message2) == ones


def test_other_kinds_of_objects_are_named_and_skipped(tmp_path: Path) -> None:
    """CANoe's objects of other kinds between the CAN frames: each CAN frame is read (CAN
    FD 64 padded as CANoe pads it, error frames with and without details), the others
    are counted by kind in a note, none is a diagnostic."""
    objects = [blf.blf_object(kind, body, stamp=5) for kind, body in blf.other_objects()]
    objects += frames_of(1)
    objects.insert(
        2, blf.blf_object(blf.CAN_FD_MESSAGE_64, blf.can_fd_64(0x123, b"\x01\x02", valid=12))
    )
    objects.insert(4, blf.blf_object(blf.CAN_ERROR, blf.can_error()))
    objects.insert(6, blf.blf_object(blf.CAN_ERROR_EXT, blf.can_error_ext()))
    objects += [blf.blf_object(kind, body, version=2) for kind, body in blf.other_objects()]
    path = tmp_path / "canoe.blf"
    path.write_bytes(blf.blf_file(objects, container_size=100))
    reader = open_input(str(path))
    items = list(reader)
    assert all(isinstance(i, CanFrame) for i in items)
    assert [i.is_fd for i in items][:1] == [True] and items[0].data == b"\x01\x02" + bytes(10)
    assert [i.is_error for i in items].count(True) == 2
    assert len(items) == 9
    assert reader.stats == {"frames": 9, "objects_skipped": 8}
    (note,) = reader.notes
    assert note.startswith("objects that carry no CAN frame were skipped: 2 application texts")
    for kind in ("2 LIN objects", "2 Ethernet objects", "2 global markers"):
        assert kind in note
    # python-can skips error frames without details; the rest it reads alike.
    assert python_can_frames(path) == [i for i in items if i.can_id or not i.is_error]


def diagnostics(items: list[Any]) -> list[str]:
    return [i.fields["detail"] for i in items if isinstance(i, Event)]


def test_an_object_of_size_0_is_said_and_reading_goes_on(tmp_path: Path) -> None:
    """python-can reads such an object for ever (its issues #1581 and #1584)."""
    objects = frames_of(1)
    broken = blf.blf_object(blf.CAN_MESSAGE, blf.can_message(0xF01, bytes(8)), size=0)
    path = tmp_path / "zero.blf"
    path.write_bytes(blf.blf_file([*objects[:3], broken, *objects[3:]]))
    items = our_items(path)
    assert len([i for i in items if isinstance(i, CanFrame)]) == 6
    (detail,) = diagnostics(items)
    assert detail == (
        "after frame 3: 48 bytes skipped: an object of type 1 with a size of 0 bytes, "
        "less than its own header (32)"
    )


@pytest.mark.parametrize(
    ("change", "said"),
    [
        ({"version": 7}, "header version 7, which Vector does not document"),
        ({"size": 20}, "a size of 20 bytes, less than its own header (32)"),
        ({"size": 2_000_000_000}, "a size of 2,000,000,000 bytes, more than a CAN message"),
        # read as it says, it would swallow the next five objects
        ({"size": 304}, "a size of 304 bytes, more than a CAN message can hold"),
    ],
)
def test_a_damaged_object_header_is_said(tmp_path: Path, change: dict[str, int], said: str) -> None:
    objects = frames_of(1)
    objects[2] = blf.blf_object(blf.CAN_MESSAGE, blf.can_message(0xF01, bytes(8)), **change)
    path = tmp_path / "damaged.blf"
    path.write_bytes(blf.blf_file(objects, containers="stored"))
    items = our_items(path)
    assert len([i for i in items if isinstance(i, CanFrame)]) == 5
    assert any(said in detail for detail in diagnostics(items)), diagnostics(items)


@pytest.mark.parametrize("containers", ["none", "stored"])
def test_a_file_cut_at_an_objects_end_is_said_from_its_header(
    tmp_path: Path, containers: str
) -> None:
    """A copy that stopped between two objects reads without damage, but the header,
    written when the file was closed, still gives the whole file's size."""
    objects = frames_of(1)
    whole = blf.blf_file(objects, containers=containers, container_size=3 * len(objects[0]))
    kept = whole[: len(whole) - len(blf.blf_file(objects[3:], containers=containers)) + 144]
    path = tmp_path / "cut.blf"
    path.write_bytes(kept)
    items = our_items(path)
    frames = [i for i in items if isinstance(i, CanFrame)]
    assert len(frames) == 3
    assert diagnostics(items) == [
        f"the BLF file is cut off at byte {len(kept):,} of the {len(whole):,} its header "
        "gives (as a copy that did not finish leaves it): the 3 frames before the cut were read"
    ]


def test_an_object_longer_than_any_in_a_can_log_is_said(tmp_path: Path) -> None:
    """Of any kind: the reader keeps no more than that while it waits for an object."""
    objects = frames_of(1)
    objects[2] = blf.blf_object(65, blf.app_text("CAN1;bus"), size=2_000_000_000)
    path = tmp_path / "huge.blf"
    path.write_bytes(blf.blf_file(objects, containers="stored"))
    items = our_items(path)
    assert len([i for i in items if isinstance(i, CanFrame)]) == 5
    assert any("more than any object of a CAN log" in d for d in diagnostics(items))


def test_bytes_that_are_no_object_are_said(tmp_path: Path) -> None:
    objects = frames_of(1)
    objects.insert(3, b"not an object at all, just bytes")
    path = tmp_path / "junk.blf"
    path.write_bytes(blf.blf_file(objects))
    items = our_items(path)
    assert len([i for i in items if isinstance(i, CanFrame)]) == 6
    assert diagnostics(items) == ["after frame 3: 32 bytes skipped: no BLF object starts there"]


def test_not_a_blf_file_is_a_usage_error(tmp_path: Path) -> None:
    path = tmp_path / "x.blf"
    path.write_bytes(b"LOGX" + bytes(200))
    with pytest.raises(UsageError, match="does not start with a BLF header"):
        open_input(str(path))


# -- damage anywhere ---------------------------------------------------------------------


def sample_file(layout: str) -> bytes:
    objects = [blf.blf_object(kind, body, stamp=3) for kind, body in blf.other_objects()[:2]]
    objects += frames_of(1) + frames_of(2) + frames_of(3, blf.CAN_MESSAGE2)
    return blf.blf_file(objects, containers=layout, container_size=150)


ORIGINALS = {layout: sample_file(layout) for layout in ("zlib", "stored", "none")}


@st.composite
def damaged_files(draw: st.DrawFn) -> tuple[bytes, str]:
    layout = draw(st.sampled_from(sorted(ORIGINALS)))
    data = bytearray(ORIGINALS[layout])
    for _ in range(draw(st.integers(1, 6))):
        where = draw(st.integers(144, len(data) - 1))
        kind = draw(st.sampled_from(["byte", "size", "cut", "insert", "repeat", "zero"]))
        if kind == "byte":
            data[where] = draw(st.integers(0, 255))
        elif kind == "size":  # a size or type field, as 4 bytes anywhere
            data[where : where + 4] = draw(
                st.sampled_from([0, 1, 15, 16, 31, 2**31, 2**32 - 1])
            ).to_bytes(4, "little")
        elif kind == "cut":
            del data[where:]
            break
        elif kind == "insert":
            data[where:where] = draw(st.binary(max_size=40))
        elif kind == "repeat":
            data[where:where] = data[where : where + draw(st.integers(1, 120))]
        else:
            data[where : where + 16] = bytes(16)
    return bytes(data), layout


@settings(
    max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(damaged_files())
def test_damage_anywhere_is_read_through_and_said(tmp_path: Path, case: tuple[bytes, str]) -> None:
    """Whatever the damage: the reading ends (in bounded time), raises nothing, and a
    file that gives fewer frames than it had says why (a diagnostic or a note)."""
    data, _ = case
    path = tmp_path / "damaged.blf"
    path.write_bytes(data)
    result: list[Any] = []

    def read() -> None:
        with BlfReader(str(path)) as reader:
            result.append((list(reader), reader))

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    thread.join(10)
    assert not thread.is_alive(), "the reader did not end"
    items, reader = result[0]
    frames = [i for i in items if isinstance(i, CanFrame)]
    said = [i for i in items if isinstance(i, Event) and i.fields["kind"] == BAD_FRAME]
    assert all(isinstance(i, (CanFrame, Event)) for i in items)
    assert reader.stats["frames"] == len(frames)
    if len(frames) < 18:  # the file held 18 frames and 2 objects of other kinds
        assert said or sum(reader.skipped.values()) > 2
