"""ROS 2 bags: ros2_socketcan's can_msgs/msg/Frame in a rosbag2 MCAP decodes like the CAN log."""

from __future__ import annotations

import json
import struct
import tempfile
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.cli import main
from analyzer.errors import InputError
from analyzer.inputs import open_input
from analyzer.mcapio.read.info import recording_info
from analyzer.mcapio.read.ros_can import RosFrameError, frame_from_cdr
from analyzer.protocol.types import BAD_FRAME, CanFrame, Event
from tests.rosbag2_files import (
    FD_FRAME_DEFINITION,
    FD_FRAME_TYPE,
    FRAME_DEFINITION,
    FRAME_TYPE,
    TYPE_HASH,
    cdr_fd_frames,
    cdr_frames,
    ros1_bag,
    ros1_mcap,
    rosbag2_mcap,
    write,
)

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "flight-candump.log"
TOPIC = "/from_can_bus"


@pytest.fixture(scope="module")
def log_frames() -> list[CanFrame]:
    frames = [item for item in open_input(str(SAMPLE)) if isinstance(item, CanFrame)]
    assert len(frames) == 629
    return frames


def _as_on_topic(frames: list[CanFrame]) -> list[CanFrame]:
    return [replace(frame, channel=TOPIC) for frame in frames]


def _read(path: Path) -> list[CanFrame | Event]:
    return [item for item in open_input(str(path)) if isinstance(item, CanFrame | Event)]


def test_rosbag2_mcap_holds_the_frames_of_the_log(tmp_path: Path, log_frames: list) -> None:
    path = write(tmp_path / "flight_0.mcap", rosbag2_mcap(log_frames))
    items = _read(path)
    # every frame, in order, its time the driver's header stamp, its channel the topic
    assert items == _as_on_topic(log_frames)


def test_frames_agree_with_mcap_ros2_support(tmp_path: Path, log_frames: list) -> None:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    path = write(tmp_path / "flight_0.mcap", rosbag2_mcap(log_frames))
    reference = []
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        decoded = list(reader.iter_decoded_messages())
    for _, channel, _, ros in decoded:
        stamp = ros.header.stamp.sec * 10**9 + ros.header.stamp.nanosec
        assert channel.topic == TOPIC and ros.header.frame_id == "can"
        reference.append(
            CanFrame(stamp / 10**9, ros.id, bytes(ros.data)[: ros.dlc], ros.is_extended, TOPIC)
        )
    assert _read(path) == reference


def test_decode_gives_the_events_of_the_log(
    tmp_path: Path, log_frames: list, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path / "flight_0.mcap", rosbag2_mcap(log_frames))

    def events(source: str) -> list[dict]:
        assert main(["decode", source, "--json"]) == 0
        lines = capsys.readouterr().out.splitlines()
        out = [json.loads(line) for line in lines]
        for event in out:
            event.pop("source")
        return [e for e in out if e.get("kind") != "bad_line"]

    from_bag = events(str(path))
    assert len(from_bag) > 300
    assert from_bag == events(str(SAMPLE))


def test_info_calls_a_finished_bag_finished(
    tmp_path: Path, log_frames: list, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path / "flight_0.mcap", rosbag2_mcap(log_frames, extra_topics=["/rosout"]))
    info = recording_info(path)
    assert info.closed and not info.recovered and not info.damage
    topics = {t.topic: (t.schema, t.count) for t in info.topics}
    assert topics[TOPIC] == (FRAME_TYPE, 629)
    assert info.tally.frames == 629  # the figures come from the frames, decoded again
    assert "decoded again" in info.stats_from
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "finished)" in out.splitlines()[0]
    assert "NOT CLOSED" not in out
    assert f"{TOPIC}" in out and FRAME_TYPE in out
    assert "written by  libmcap 1.4.1, profile ros2" in out  # its header record


def test_unfinished_bag_is_recovered(tmp_path: Path, log_frames: list) -> None:
    # rosbag2 killed: the chunks written so far, no summary and no footer
    path = write(tmp_path / "flight_0.mcap", rosbag2_mcap(log_frames, finished=False))
    info = recording_info(path)
    assert info.recovered
    assert _read(path)[:-1] == _as_on_topic(log_frames)  # then an `incomplete` note
    # cut in the middle of its only chunk: nothing readable, and that is said
    whole = path.read_bytes()
    cut = write(tmp_path / "cut.mcap", whole[: len(whole) // 2])
    (note,) = _read(cut)
    assert isinstance(note, Event) and note.fields["kind"] == "incomplete"


def test_can_fd_frames_of_ros2_socketcan(tmp_path: Path, log_frames: list) -> None:
    fd = [
        CanFrame(1715680800.5 + k / 100, 0x18FEF100 + k, bytes(range(n)), True, TOPIC, is_fd=True)
        for k, n in enumerate((0, 8, 12, 64))
    ]
    messages = cdr_fd_frames(fd)
    bag = rosbag2_mcap([], messages=messages, schema=(FD_FRAME_TYPE, FD_FRAME_DEFINITION))
    assert _read(write(tmp_path / "fd.mcap", bag)) == fd
    log_time, data = messages[3]
    too_long = data[: -(4 + 64)] + struct.pack("<I", 65) + bytes(65)  # 65 data bytes
    bag = rosbag2_mcap(
        [], messages=[(log_time, too_long)], schema=(FD_FRAME_TYPE, FD_FRAME_DEFINITION)
    )
    (note,) = _read(write(tmp_path / "fd_bad.mcap", bag))
    assert isinstance(note, Event) and "at most 64" in note.fields["detail"]


def test_message_that_is_not_a_frame_becomes_a_diagnostic(tmp_path: Path, log_frames: list) -> None:
    messages = cdr_frames(log_frames[:5])
    log_time, data = messages[2]
    bad = bytearray(data)
    bad[len(bad) - 9] = 9  # dlc 9
    messages[2] = (log_time, bytes(bad))
    path = write(tmp_path / "bad.mcap", rosbag2_mcap([], messages=messages))
    items = _read(path)
    assert items[:2] + items[3:] == _as_on_topic(log_frames[:2] + log_frames[3:5])
    assert isinstance(items[2], Event)
    assert items[2].fields["kind"] == BAD_FRAME
    assert "dlc 9 is over 8" in items[2].fields["detail"]


def test_mcap_without_usable_channel_lists_its_channels(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(
        tmp_path / "chat.mcap",
        rosbag2_mcap([], messages=[], topic=None, extra_topics=["/chatter", "/rosout"]),
    )
    assert main(["decode", str(path)]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith("gimbal-analyzer decode: error: ")
    assert "no channel this tool can read" in lines[0]
    assert lines[1:] == [
        "  /chatter  std_msgs/msg/String (ros2msg/cdr)",
        "  /rosout  std_msgs/msg/String (ros2msg/cdr)",
    ]
    # unfinished (no summary): the channels are known once the file was read through
    unfinished = rosbag2_mcap(
        [], messages=[], topic=None, extra_topics=["/chatter"], finished=False
    )
    assert main(["decode", str(write(tmp_path / "chat_0.mcap", unfinished))]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert "no channel this tool can read" in lines[0]
    assert lines[1:] == ["  /chatter  std_msgs/msg/String (ros2msg/cdr)"]


def test_stored_events_of_a_bag_are_refused(
    tmp_path: Path, log_frames: list, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path / "flight_0.mcap", rosbag2_mcap(log_frames[:3]))
    assert main(["decode", "--stored", str(path)]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert "--stored reads the events this tool records" in lines[0]
    assert lines[1] == f"  {TOPIC}  {FRAME_TYPE} (ros2msg/cdr)"


def rosbags_bag(directory: Path, frames: list[CanFrame], plugin: str, *, fd: bool = False) -> Path:
    """A rosbag2 bag written by rosbags (another writer of both storages)."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    storage = StoragePlugin.MCAP if plugin == "mcap" else StoragePlugin.SQLITE3
    msgtype, msgdef = (FD_FRAME_TYPE, FD_FRAME_DEFINITION) if fd else (FRAME_TYPE, FRAME_DEFINITION)
    with Writer(directory, version=9, storage_plugin=storage) as writer:
        connection = writer.add_connection(TOPIC, msgtype, msgdef=msgdef, rihs01=TYPE_HASH)
        for log_time, data in (cdr_fd_frames if fd else cdr_frames)(frames):
            writer.write(connection, log_time, data)
    (path,) = directory.glob(f"*.{plugin}")
    return path


def test_bag_written_by_rosbags_decodes_too(tmp_path: Path, log_frames: list) -> None:
    path = rosbags_bag(tmp_path / "bag", log_frames[:50], "mcap")
    assert _read(path) == _as_on_topic(log_frames[:50])


def test_rosbag2_sqlite3_storage_decodes_too(tmp_path: Path, log_frames: list) -> None:
    path = rosbags_bag(tmp_path / "bag", log_frames, "db3")
    assert _read(path) == _as_on_topic(log_frames)
    fd = [replace(f, is_fd=True, data=f.data * 2) for f in _as_on_topic(log_frames[:20])]
    assert _read(rosbags_bag(tmp_path / "fd", fd, "db3", fd=True)) == fd


def test_ros1_bag_holds_the_frames_of_the_log(tmp_path: Path, log_frames: list) -> None:
    path = ros1_bag(tmp_path / "flight.bag", log_frames)
    on_topic = [replace(frame, channel="/received_messages") for frame in log_frames]
    assert _read(path) == on_topic


def test_ros1_bag_converted_to_mcap_decodes_too(tmp_path: Path, log_frames: list) -> None:
    path = write(tmp_path / "flight.mcap", ros1_mcap(log_frames))
    assert _read(path) == [replace(f, channel="/received_messages") for f in log_frames]


def test_bag_without_can_topic_lists_its_topics(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from rosbags.rosbag1 import Writer as Ros1Writer

    path = tmp_path / "chat.bag"
    with Ros1Writer(path) as writer:
        writer.add_connection("/chatter", "std_msgs/msg/String", msgdef="string data", md5sum="x")
    assert main(["decode", str(path)]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert "no can_msgs/Frame topic to read" in lines[0]
    assert lines[1:] == ["  /chatter  std_msgs/msg/String"]


def test_damaged_ros1_bag_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "bad.bag"
    path.write_bytes(b"#ROSBAG V2.0\n" + bytes(range(256)) * 4)
    assert main(["decode", str(path)]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith("gimbal-analyzer decode: error: ") and "not a readable ROS bag" in line


def test_ros1_bag_cut_short_or_with_a_hole(
    tmp_path: Path, log_frames: list, capsys: pytest.CaptureFixture[str]
) -> None:
    whole = ros1_bag(tmp_path / "flight.bag", log_frames).read_bytes()
    # killed recorder: no index at the end, which rosbag reindex would rebuild
    cut = write(tmp_path / "cut.bag", whole[: len(whole) * 2 // 3])
    assert main(["decode", str(cut)]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert "not a readable ROS bag" in line and "rosbag reindex" in line
    # zeroed bytes in the middle: the frames before, then a note where reading stopped
    holed = bytearray(whole)
    holed[len(whole) // 2 : len(whole) // 2 + 40] = bytes(40)
    items = _read(write(tmp_path / "hole.bag", bytes(holed)))
    frames = [item for item in items if isinstance(item, CanFrame)]
    assert 0 < len(frames) < len(log_frames)
    assert frames == [replace(f, channel="/received_messages") for f in log_frames[: len(frames)]]
    assert isinstance(items[-1], Event) and items[-1].fields["kind"] == "incomplete"


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    cut=st.one_of(st.none(), st.integers(0, 60_000)),
    flips=st.lists(st.tuples(st.integers(0, 60_000), st.integers(1, 255)), max_size=4),
)
def test_damaged_bags_give_frames_and_diagnostics_never_a_traceback(
    cut: int | None, flips: list[tuple[int, int]]
) -> None:
    data = bytearray(_BAG)
    for at, mask in flips:
        if at < len(data):
            data[at] ^= mask
    if cut is not None:
        data = data[:cut]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bag.mcap"
        path.write_bytes(bytes(data))
        try:
            items = _read(path)
        except InputError:  # not recognisable as MCAP, or no usable channel left
            return
    frames = [item for item in items if isinstance(item, CanFrame)]
    assert len(frames) <= len(_BAG_FRAMES)
    if not flips:  # cut short only: a prefix of the frames, then the cut is said
        assert frames == _BAG_FRAMES[: len(frames)]
        if len(frames) < len(_BAG_FRAMES):
            assert any(isinstance(i, Event) and i.fields["kind"] == "incomplete" for i in items)


_BAG_FRAMES = [
    replace(f, channel=TOPIC) for f in open_input(str(SAMPLE)) if isinstance(f, CanFrame)
]
_BAG = rosbag2_mcap(_BAG_FRAMES)


# -- the CDR layout, against arbitrary bytes and against mcap-ros2-support's encoder ----------

_frames = st.builds(
    lambda ext, can_id, data, sec, ns, remote: CanFrame(
        (sec * 10**9 + ns) / 10**9,
        can_id & (0x1FFFFFFF if ext else 0x7FF),
        b"" if remote else data,
        ext,
        TOPIC,
        remote,
        remote_dlc=len(data) if remote else 0,
    ),
    st.booleans(),
    st.integers(0, 0x1FFFFFFF),
    st.binary(max_size=8),
    # a ROS time's seconds are an int32; a float time in the last second before 2**31
    # may round up to 2**31, which no stamp can carry
    st.integers(1, 2**31 - 2),
    st.integers(0, 10**9 - 1),
    st.booleans(),
)


@settings(max_examples=200, deadline=None)
@given(st.lists(_frames, min_size=1, max_size=5))
def test_cdr_frames_round_trip(frames: list[CanFrame]) -> None:
    decoded = [frame_from_cdr(data, TOPIC, 0) for _, data in cdr_frames(frames)]
    assert decoded == frames


@settings(max_examples=500, deadline=None)
@given(st.binary(max_size=64))
def test_any_bytes_give_a_frame_or_a_reason(data: bytes) -> None:
    try:
        frame = frame_from_cdr(data, TOPIC, 5)
    except RosFrameError as exc:
        assert str(exc)
        return
    assert len(frame.data) <= 8 and 0 <= frame.can_id <= 0x1FFFFFFF


def test_big_endian_cdr_is_read() -> None:
    body = struct.pack(">iII4s", 7, 5, 4, b"can\0") + struct.pack(
        ">I4B8s", 0x123, 0, 0, 0, 2, b"\1\2"
    )
    frame = frame_from_cdr(b"\x00\x00\x00\x00" + body, TOPIC, 0)
    assert frame == CanFrame(7.000000005, 0x123, b"\1\2", False, TOPIC)
