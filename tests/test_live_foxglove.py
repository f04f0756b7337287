"""--foxglove: the decoded stream served live to Foxglove (foxglove-sdk server, foxglove.sdk.v1).

A client speaking Foxglove's WebSocket protocol (``tests/foxglove_client.py``) sees the
channels a recording has, with the same schemas, and messages equal to the recorded ones;
late joiners get the channels at once; a client that stops reading never holds the
recording back, and the recording is byte for byte the same with or without clients.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import json
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st
from mcap.reader import make_reader
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from analyzer.inputs import open_input
from analyzer.live.attach import foxglove_status
from analyzer.live.options import ListenAddress, listen_words, parse_listen_address
from analyzer.live.server import FoxgloveLive, status_words
from analyzer.mcapio.write.sink import McapSink
from analyzer.pipeline import Batch, Pipeline, run_items
from analyzer.protocol.types import CanFrame
from analyzer.tui.state import MonitorState
from analyzer.tui.status_bar import StatusInfo, render_status
from tests.foxglove_client import FoxgloveClient
from tests.platforms import posix_signals
from tests.test_record_command import FakeIdu

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "samples" / "flight-candump.log"
LOCAL = ListenAddress("127.0.0.1", 0)  # a free port on this machine only
METADATA = {"source": "test", "created": "2026-01-01T00:00:00+0000"}
BIG_BACKLOG = 1_000_000  # clients that read everything: nothing may be dropped


def sample_items(repeat: int = 1) -> list[Any]:
    """The sample flight log's frames, ``repeat`` times one after the other in time."""
    items = list(open_input(str(SAMPLE)))
    frames = [item for item in items if isinstance(item, CanFrame)]
    span = frames[-1].time - frames[0].time + 0.01
    return [
        dataclasses.replace(item, time=item.time + n * span) if isinstance(item, CanFrame) else item
        for n in range(repeat)
        for item in items
    ]


def recorded(path: Path) -> tuple[dict[str, dict[str, Any]], dict[str, list[tuple[int, bytes]]]]:
    """Channels (topic -> encoding, schema name, schema, metadata) and messages (publish
    time, data) by topic, in file order, as the mcap library reads them. The publish time is
    the message's own time, which the live server sends (the log time of a message older
    than a chunk already written is raised to that chunk's end)."""
    channels: dict[str, dict[str, Any]] = {}
    messages: dict[str, list[tuple[int, bytes]]] = {}
    with path.open("rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            assert schema is not None
            channels[channel.topic] = {
                "encoding": channel.message_encoding,
                "schemaName": schema.name,
                "schemaEncoding": schema.encoding,
                "schema": schema.data.decode(),
                "metadata": dict(channel.metadata),
            }
            messages.setdefault(channel.topic, []).append((message.publish_time, message.data))
    return channels, messages


def advertised(channel: dict[str, Any]) -> dict[str, Any]:
    return {key: channel[key] for key in ("encoding", "schemaName", "schemaEncoding", "schema")} | {
        "metadata": channel.get("metadata", {})
    }


class Drained:
    """A sink put before the server: at the end it waits until ``client`` has every
    message the server sent, so that stopping the server loses none of them."""

    def __init__(self, live: FoxgloveLive, client: FoxgloveClient) -> None:
        self.live = live
        self.client = client

    def handle(self, batch: Batch) -> None:
        pass

    def close(self) -> None:
        sent = self.live.status().messages
        assert self.client.wait_for(lambda: len(self.client.messages) >= sent, 20)


def record(
    path: Path, items: list[Any], live: FoxgloveLive | None, client: FoxgloveClient | None = None
) -> None:
    """Record ``items`` as ``convert`` does (fixed batches), teeing to ``live`` if given."""
    sink = McapSink(path, metadata=METADATA, flush_interval=None, tee=live)
    sinks: list[Any] = [sink]
    if live is not None:
        sinks += [Drained(live, client), live] if client is not None else [live]
    pipeline = Pipeline(sinks)
    run_items(items, pipeline)
    assert not pipeline.failures


# -- the option -------------------------------------------------------------------------------


def test_listen_address_grammar() -> None:
    assert parse_listen_address("8765") == ListenAddress("127.0.0.1", 8765)
    assert parse_listen_address("0.0.0.0:9000") == ListenAddress("0.0.0.0", 9000)
    assert parse_listen_address("[::1]:9000") == ListenAddress("::1", 9000)
    for bad in ("", "x", "host:", ":80", "70000", "::1:9000"):
        with pytest.raises(argparse.ArgumentTypeError):
            parse_listen_address(bad)


@given(st.text(max_size=40))
def test_any_address_text_is_an_address_or_one_clear_error(text: str) -> None:
    try:
        listen = parse_listen_address(text)
    except argparse.ArgumentTypeError as exc:
        assert repr(text.strip()) in str(exc)
    else:
        assert 0 <= listen.port <= 65535 and listen.host


def test_all_interfaces_is_said_with_the_address() -> None:
    words = listen_words(ListenAddress("0.0.0.0", 8765), 8765)
    assert "all interfaces" in words and "ws://0.0.0.0:8765" in words
    assert "127.0.0.1:8765" in words  # and how to keep it on this machine
    local = listen_words(ListenAddress("127.0.0.1", 8765), 8765)
    assert local == "serving the live stream to Foxglove on ws://127.0.0.1:8765"


# -- the server -------------------------------------------------------------------------------


def test_live_messages_equal_the_recorded_ones_and_the_file_does_not_change(
    tmp_path: Path,
) -> None:
    items = sample_items(3)
    record(tmp_path / "alone.mcap", items, None)

    live = FoxgloveLive(LOCAL, backlog=BIG_BACKLOG)
    record(tmp_path / "no-client.mcap", items, live)  # closes the server at the end

    live = FoxgloveLive(LOCAL, backlog=BIG_BACKLOG)
    client = FoxgloveClient(live.url)
    try:
        # subscribed to every channel (all are advertised when a client connects)
        assert client.wait_for(lambda: live.status().subscriptions == len(client.channels) > 0)
        record(tmp_path / "client.mcap", items, live, client)
        assert client.closed.wait(10)  # the server stopped with the recording
    finally:
        client.close()

    alone = (tmp_path / "alone.mcap").read_bytes()
    assert (tmp_path / "no-client.mcap").read_bytes() == alone
    assert (tmp_path / "client.mcap").read_bytes() == alone

    channels, messages = recorded(tmp_path / "alone.mcap")
    live_channels = {c["topic"]: advertised(c) for c in client.channels.values()}
    assert {topic: live_channels[topic] for topic in channels} == channels
    got = client.by_topic()
    assert set(got) == set(messages)
    for topic, live_messages in got.items():
        assert live_messages == messages[topic], topic  # all, in order, with their log times


def test_without_a_recording_it_sends_what_a_recording_holds(tmp_path: Path) -> None:
    """monitor records nothing: the server encodes the batches itself, to the same bytes."""
    items = sample_items(2)
    record(tmp_path / "reference.mcap", items, None)
    live = FoxgloveLive(LOCAL, backlog=BIG_BACKLOG, encode=True)
    client = FoxgloveClient(live.url)
    try:
        assert client.wait_for(lambda: live.status().subscriptions == len(client.channels) > 0)
        run_items(items, Pipeline([Drained(live, client), live]))
        assert client.closed.wait(10)
    finally:
        client.close()
    channels, messages = recorded(tmp_path / "reference.mcap")
    got = client.by_topic()
    assert set(got) == set(messages)
    for topic, live_messages in got.items():  # sent as they come; a file orders a batch by time
        assert sorted(live_messages) == sorted(messages[topic]), topic
    live_channels = {c["topic"]: advertised(c) for c in client.channels.values()}
    assert {topic: live_channels[topic] for topic in channels} == channels


def test_a_late_joiner_gets_every_channel_at_once(tmp_path: Path) -> None:
    items = sample_items()
    live = FoxgloveLive(LOCAL)
    sink = McapSink(tmp_path / "late.mcap", metadata=METADATA, flush_interval=None, tee=live)
    pipeline = Pipeline([sink, live])
    pipeline.feed(items)
    pipeline.deliver()
    client = FoxgloveClient(live.url, subscribe=False)
    try:
        assert client.wait_for(lambda: client.first_advertise is not None, 10)
        first = {c["topic"]: advertised(c) for c in client.first_advertise or []}
    finally:
        client.close()
        pipeline.finish()
    channels, _ = recorded(tmp_path / "late.mcap")
    # all of them, in the first advertise, as recorded (and those a recording may get later)
    assert {topic: first[topic] for topic in channels} == channels
    assert {c["metadata"]["role"] for c in channels.values()} == {"raw", "event", "view"}
    assert {"/stream/bytes", "/gimbal/ranging/fix", "/analysis/response"} <= set(first)


@pytest.mark.slow
def test_a_client_that_stops_reading_does_not_hold_the_recording_back(tmp_path: Path) -> None:
    items = sample_items(100)
    first, rest = items[:200], items[200:]

    def record_in_two(path: Path, live: FoxgloveLive | None) -> Pipeline:
        sink = McapSink(path, metadata=METADATA, flush_interval=None, tee=live)
        pipeline = Pipeline([sink] if live is None else [sink, live])
        pipeline.feed(first)
        pipeline.deliver()
        if live is not None:  # a client subscribes to every channel, then reads no more
            client = FoxgloveClient(live.url, reading=False)
            assert client.wait_for(lambda: live.status().subscriptions == len(client.channels))
        started = time.perf_counter()
        run_items(rest, pipeline)
        timings.append(time.perf_counter() - started)
        assert not pipeline.failures
        if live is not None:
            statuses.append(live.status())
            words.append(status_words(live))  # what record's status line shows
            shown = foxglove_status(live)  # and what the monitor's status bar shows
            assert shown is not None
            bars.append(
                render_status(
                    MonitorState(), StatusInfo(source="x", live=shown()[0], live_alert=shown()[1])
                ).plain
            )
            alerts.append(shown()[1])
            client.close()
        return pipeline

    timings: list[float] = []
    statuses: list[Any] = []
    words: list[str] = []
    bars: list[str] = []
    alerts: list[bool] = []
    record_in_two(tmp_path / "alone.mcap", None)
    record_in_two(tmp_path / "slow.mcap", FoxgloveLive(LOCAL, backlog=256))
    assert (tmp_path / "slow.mcap").read_bytes() == (tmp_path / "alone.mcap").read_bytes()
    status = statuses[0]
    assert status.messages > 100_000
    assert status.drop_reports >= 1  # the SDK said it dropped messages to the slow client
    assert "1 client SLOW CLIENT, messages to it dropped" in words[0]
    assert "SLOW CLIENT, messages to it dropped" in bars[0] and alerts == [True]
    alone_s, slow_s = timings
    assert slow_s < 3 * alone_s + 2.0, timings  # generous: a stalled one would never finish


def test_record_status_line_names_the_server_and_its_clients(tmp_path: Path) -> None:
    from analyzer.capture import Capture
    from analyzer.commands.record import StatusLine
    from analyzer.live.attach import foxglove_note
    from analyzer.sources import open_source

    live = FoxgloveLive(LOCAL)
    client = FoxgloveClient(live.url)
    try:
        assert client.wait_for(lambda: live.status().watching == 1)
        status = StatusLine(io.StringIO(), str(tmp_path / "x.mcap"))
        status.capture = Capture(open_source(f"file:{SAMPLE}"), [])
        status.notes.append(lambda: foxglove_note(live))
        assert f"foxglove :{live.port} 1 client" in status.line()
    finally:
        client.close()
        live.close()
        status.capture.source.close()


def test_the_old_subprotocol_is_refused_and_counted() -> None:
    live = FoxgloveLive(LOCAL)
    try:
        with pytest.raises(InvalidStatus):
            connect(live.url, subprotocols=["foxglove.websocket.v1"], open_timeout=10)
        deadline = time.monotonic() + 5
        while live.status().refused < 1 and time.monotonic() < deadline:
            time.sleep(0.02)
        assert live.status().refused == 1
    finally:
        live.close()


# -- the command ------------------------------------------------------------------------------


@posix_signals
@pytest.mark.slow
def test_record_serves_the_live_stream_while_recording(tmp_path: Path) -> None:
    idu = FakeIdu()
    path = tmp_path / "flight.mcap"
    proc = subprocess.Popen(
        [
            *(sys.executable, "-m", "analyzer", "record"),
            *("--source", f"tcp:127.0.0.1:{idu.port}", "-o", str(path)),
            *("--foxglove", "127.0.0.1:0"),
        ],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        encoding="utf-8",
    )
    client = None
    try:
        assert proc.stderr is not None
        said = proc.stderr.readline()  # said on start, before anything is captured
        assert said.startswith("foxglove: serving the live stream to Foxglove on ws://127.0.0.1:")
        url = said.split(" on ")[-1].strip()
        client = FoxgloveClient(url)
        assert client.wait_for(lambda: len(client.messages) >= 100, 20)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=20)
    finally:
        if client is not None:
            client.close()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        idu.close()
    assert proc.returncode == 0, err
    assert "foxglove: served" in err
    channels, messages = recorded(path)
    got = client.by_topic()
    assert {"/stream/bytes", "/gimbal/attitude"} <= set(got)
    for topic, live_messages in got.items():
        assert advertised(client.channels_by_topic()[topic]) == channels[topic]
        start = messages[topic].index(live_messages[0])
        assert messages[topic][start : start + len(live_messages)] == live_messages, topic
    attitude = [json.loads(data) for _, data in got["/gimbal/attitude"]]
    assert all(message["topic"] == "/gimbal/attitude" for message in attitude)
