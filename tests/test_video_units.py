"""Access units, parameter sets, frame times and --video specs, without a camera."""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from analyzer.errors import UsageError
from analyzer.mcapio.schema_subset import foxglove_problems
from analyzer.mcapio.write.video import (
    COMPRESSED_IMAGE_SCHEMA,
    COMPRESSED_VIDEO_SCHEMA,
    message_json,
)
from analyzer.video.annexb import (
    H264,
    START_CODE,
    ParameterSets,
    annex_b,
    nal_type,
    parameter_sets_from_extradata,
    split_nals,
)
from analyzer.video.frame_clock import FrameClock, Stamp
from analyzer.video.spec import PASSWORD_ENV, parse_video_spec, video_specs

# SPS and PPS exactly as the test camera's x264 sends them (extradata of the RTSP stream).
SPS = bytes.fromhex("6742c01eda0280bfe5c05a8303035280000003008000001e478b1750")
PPS = bytes.fromhex("68ce3c80")
IDR = bytes.fromhex("65888040") + bytes(range(1, 60))
P_SLICE = bytes.fromhex("419a2020") + bytes(range(1, 40))
AUD = bytes.fromhex("0910")

# A NAL unit never holds 00 00 00/01/02/03 (emulation prevention) nor ends with 00.
nal_units = st.binary(min_size=1, max_size=64).filter(
    lambda b: b"\x00\x00" not in b and not b.endswith(b"\x00")
)


@given(st.lists(nal_units, max_size=8), st.sampled_from([b"\x00\x00\x01", START_CODE]))
def test_split_nals_gives_back_the_units_it_was_made_of(units: list[bytes], code: bytes) -> None:
    assert split_nals(b"".join(code + u for u in units)) == units


@given(st.binary(max_size=300))
def test_any_bytes_split_without_an_error_and_without_losing_payload(data: bytes) -> None:
    units = split_nals(data)
    assert sum(len(u) for u in units) <= len(data)
    assert all(units)
    for unit in units:
        assert unit in data


@given(st.binary(max_size=200))
def test_damaged_extradata_gives_what_it_can_never_an_error(data: bytes) -> None:
    for codec in ("h264", "h265"):
        for unit in parameter_sets_from_extradata(codec, data):
            assert unit in data


def test_parameter_sets_from_annex_b_and_avcc_extradata() -> None:
    annexb = START_CODE + SPS + START_CODE + PPS
    assert parameter_sets_from_extradata(H264, annexb) == [SPS, PPS]
    avcc = (
        bytes([1, SPS[1], SPS[2], SPS[3], 0xFF, 0xE1])
        + len(SPS).to_bytes(2, "big")
        + SPS
        + bytes([1])
        + len(PPS).to_bytes(2, "big")
        + PPS
    )
    assert parameter_sets_from_extradata(H264, avcc) == [SPS, PPS]


def test_a_keyframe_gets_the_parameter_sets_in_front_once_in_decoding_order() -> None:
    params = ParameterSets(H264, [SPS, PPS])
    # as x264 zerolatency + rtph264pay deliver it: slices with the sets repeated between them
    data, key = annex_b(H264, [AUD, IDR, SPS, PPS, IDR], params)
    assert key
    assert [nal_type(H264, u) for u in split_nals(data)] == [9, 7, 8, 5, 5]
    data, key = annex_b(H264, [P_SLICE], params)
    assert not key and split_nals(data) == [P_SLICE]


def test_frames_of_the_opening_burst_keep_the_stream_spacing() -> None:
    clock: FrameClock[int] = FrameClock(settle_s=1.0)
    out: list[tuple[float, int]] = []
    t0 = 1_000.0
    for n in range(30):  # one second of frames buffered by the camera, arriving at once
        out += clock.add(Stamp(n / 30, t0 + 0.001 * n), n)
    assert out == []  # held until the anchor is known
    released_at = None
    for n in range(30, 90):  # then live, each 40 ms after capture
        out += clock.add(Stamp(n / 30, t0 - 1.0 + n / 30 + 0.04), n)
        if out and released_at is None:
            released_at = n
    assert released_at is not None and released_at < 30 + 12  # about 0.3 s after the burst
    times = [t for t, _ in out]
    assert [n for _, n in out] == list(range(len(out)))
    steps = [b - a for a, b in itertools.pairwise(times)]
    assert steps == pytest.approx([1 / 30] * len(steps), abs=1e-6)
    assert times[0] == pytest.approx(t0 - 1.0 + 0.04, abs=1e-6)
    assert clock.source == "arrival"


def test_rtcp_wallclock_wins_for_held_and_later_frames() -> None:
    clock: FrameClock[int] = FrameClock(settle_s=5.0)
    out = clock.add(Stamp(0.0, 40.3), 0) + clock.add(Stamp(1 / 30, 40.31), 1)
    out += clock.add(Stamp(2 / 30, 40.32, wallclock=40.0 + 2 / 30), 2)
    assert [t for t, _ in out] == pytest.approx([40.0, 40.0 + 1 / 30, 40.0 + 2 / 30])
    assert clock.source == "rtcp"


def test_rtcp_times_far_from_the_local_clock_are_not_believed() -> None:
    # a camera without NTP, or a sender report from before the stream restarted
    clock: FrameClock[int] = FrameClock(settle_s=0.1)
    out: list[tuple[float, int]] = []
    for n in range(10):
        out += clock.add(Stamp(n / 30, 1000.05 + n / 30, wallclock=900.0 + n / 30), n)
    assert clock.source == "arrival"
    assert out[0][0] == pytest.approx(1000.05, abs=1e-6)


@given(
    st.lists(
        st.tuples(
            st.floats(0, 1e4, allow_nan=False),
            st.floats(0, 1e4, allow_nan=False),
            st.none() | st.floats(0, 1e4, allow_nan=False),
        ),
        max_size=50,
    )
)
def test_frame_times_never_go_back_and_no_frame_is_lost(
    stamps: list[tuple[float, float, float | None]],
) -> None:
    clock: FrameClock[int] = FrameClock(settle_s=0.5)
    out: list[tuple[float, int]] = []
    for n, (stream_s, arrival, wallclock) in enumerate(stamps):
        out += clock.add(Stamp(stream_s, arrival, wallclock), n)
    out += clock.flush()
    assert [n for _, n in out] == list(range(len(stamps)))
    assert all(a < b for a, b in itertools.pairwise(t for t, _ in out))


def test_video_specs_of_the_document_and_any_url() -> None:
    main = parse_video_spec("main")
    assert main.url == "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0"
    assert main.shown == "rtsp://admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0"
    thermal = parse_video_spec("thermal", camera="127.0.0.1:8554", password="p@ss")
    assert thermal.url.endswith("@127.0.0.1:8554/cam/realmonitor?channel=1&subtype=2")
    assert "admin:p%40ss@" in thermal.url and "p%40ss" not in thermal.shown
    front = parse_video_spec("front=rtsp://u:pw@10.0.0.9/live")
    assert (front.name, front.url, front.shown) == (
        "front",
        "rtsp://u:pw@10.0.0.9/live",
        "rtsp://u@10.0.0.9/live",
    )


def _options(*argv: str) -> argparse.Namespace:
    from analyzer.cli import build_parser

    return build_parser("record").parse_args(
        ["record", "--source", "can:vcan0", "-o", "x.mcap", *argv]
    )


def test_credentials_written_in_a_url_win_for_that_stream(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv(PASSWORD_ENV, raising=False)
    args = _options(
        "--video", "main", "--video", "bench=rtsp://bob:pw%402@10.0.0.9/live",
        "--video", "door=rtsp://10.0.0.7/live", "--video", "yard=rtsp://eve@10.0.0.8/live",
        "--camera-password", "doc-pw",
    )  # fmt: skip
    main, bench, door, yard = video_specs(args)
    assert "//admin:doc-pw@192.168.42.108:554/" in main.url
    assert bench.url == "rtsp://bob:pw%402@10.0.0.9/live"  # not the document camera's
    assert door.url == "rtsp://10.0.0.7/live"  # no user to go with a password
    assert yard.url == "rtsp://eve:doc-pw@10.0.0.8/live"  # the URL's user, the option's password


def test_the_password_from_a_file_or_the_environment_stays_out_of_the_command_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    secret = tmp_path / "camera.secret"
    secret.write_text("from-file\nsecond line ignored\n", encoding="utf-8")
    monkeypatch.setenv(PASSWORD_ENV, "from-env")
    (main,) = video_specs(_options("--video", "main", "--camera-password-file", str(secret)))
    assert "admin:from-file@" in main.url and "from-file" not in main.shown
    (main,) = video_specs(_options("--video", "main"))
    assert "admin:from-env@" in main.url
    (main,) = video_specs(_options("--video", "main", "--camera-password", "given"))
    assert "admin:given@" in main.url
    monkeypatch.delenv(PASSWORD_ENV)
    (main,) = video_specs(_options("--video", "main"))
    assert "admin:admin@" in main.url


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--camera-password", "a", "--camera-password-file", "x"], "not both"),
        (["--camera-password-file", "/nonexistent/secret"], "cannot read it"),
    ],
)
def test_a_password_option_that_cannot_be_used_is_one_line(argv: list[str], message: str) -> None:
    with pytest.raises(UsageError, match=message):
        video_specs(_options("--video", "main", *argv))


@pytest.mark.parametrize("text", ["front", "x y=rtsp://h/p", "a=http://h/p", "a=rtsp:///p", "sub3"])
def test_bad_video_specs_say_what_is_expected(text: str) -> None:
    with pytest.raises(UsageError, match="--video"):
        parse_video_spec(text)


def test_bad_camera_address() -> None:
    with pytest.raises(UsageError, match="--camera"):
        parse_video_spec("main", camera="host:99999")


@given(st.lists(st.binary(min_size=1, max_size=40), max_size=10))
def test_any_units_make_an_access_unit_without_losing_a_picture_unit(units: list[bytes]) -> None:
    params = ParameterSets(H264)
    data, _ = annex_b(H264, units, params)
    kept = split_nals(data)
    for unit in units:
        if nal_type(H264, unit) not in (7, 8, 9):  # sets and AUD are written once
            assert unit.rstrip(b"\x00") in data or not unit.rstrip(b"\x00")
    assert len(kept) <= len(units) + len(params.units()) + 1


def test_camera_schemas_are_foxglove_s_and_in_the_subset_it_reads() -> None:
    import json

    import jsonschema

    for schema in (COMPRESSED_VIDEO_SCHEMA, COMPRESSED_IMAGE_SCHEMA):
        assert foxglove_problems(schema) == []
        assert set(schema["properties"]) == {"timestamp", "frame_id", "data", "format"}
    message = json.loads(message_json("main", 1_795_527_000.25, b"\x00\x00\x00\x01\x65", "h264"))
    jsonschema.validate(message, COMPRESSED_VIDEO_SCHEMA)
    stamp = message.pop("timestamp")
    assert stamp["sec"] == 1_795_527_000 and abs(stamp["nsec"] - 250_000_000) < 1_000
    assert message == {
        "frame_id": "camera_main",
        "data": "AAAAAWU=",
        "format": "h264",
    }


def test_a_camera_link_change_leaves_the_telemetry_link_state_alone() -> None:
    from analyzer.commands.record import LinkWatch
    from analyzer.pipeline import Batch
    from analyzer.protocol.types import LINK, diagnostic
    from analyzer.tui.state import MonitorState

    telemetry = diagnostic(1.0, "tcp", LINK, "connected to 127.0.0.1:2000", state="connected")
    camera = diagnostic(
        2.0, "camera/main", LINK, "cannot open rtsp://...: 401 unauthorized", state="connect_failed"
    )
    batch = Batch([], [telemetry, camera], 2.0)
    state = MonitorState()
    state.fold(batch)
    watch = LinkWatch()
    watch.handle(batch)
    assert (state.link_state, state.link_detail) == ("connected", "connected to 127.0.0.1:2000")
    assert state.counters.errors == 0
    assert watch.status.state == "connected" and not watch.status.failing


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--source", "tcp:2000", "--video", "bogus"], "--video bogus: expected main, sub1"),
        (["--source", "tcp:2000", "--video", "main", "--video", "main"], "given twice"),
        (["--source", "tcp:2000", "--video", "main", "--camera", "h:0"], "--camera h:0"),
        (["--source", "file:x.log", "--video", "main"], "a file: replay has the times"),
        (["--source", "tcp:2000", "--video", "main", "--thumbnail-interval", "-1"], "0 (none)"),
    ],
)
def test_record_refuses_wrong_video_options_before_starting(
    args: list[str], words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analyzer.cli import main

    out = tmp_path / "x.mcap"
    assert main(["record", *args, "-o", str(out)]) == 2
    assert words in capsys.readouterr().err
    assert not out.exists()


def test_a_camera_that_refuses_the_connection_is_said_in_words_and_retried() -> None:
    import socket
    import time

    from analyzer.video.rtsp_stream import VideoStream

    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    spec = parse_video_spec(f"front=rtsp://admin:s3cr3t@127.0.0.1:{port}/live")
    stream = VideoStream(spec, backoff_initial=0.1)
    stream.start()
    time.sleep(1.0)
    stream.stop()
    _, events = stream.take()
    details = [str(e.fields["detail"]) for e in events]
    failed = [d for d in details if d.startswith("cannot open")]
    assert (
        failed
        and failed[0] == f"cannot open rtsp://admin@127.0.0.1:{port}/live: connection refused"
    )
    assert [e.fields["retry_in_s"] for e in events if e.fields["state"] == "reconnecting"][:2] == [
        0.1,
        0.2,
    ]
    assert all("s3cr3t" not in d for d in details)
