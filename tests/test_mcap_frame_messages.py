"""The /can/frames message of every frame is ``can_frame_json`` of it, whichever path writes it."""

from __future__ import annotations

import io
import math

import orjson
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader

from analyzer.mcapio.channels import FLOAT_AS_REPR_FROM, TOPIC_CAN_FRAMES, can_frame_json
from analyzer.mcapio.log_time import time_ns
from analyzer.mcapio.write.channel_registry import ChannelRegistry, default_schemas
from analyzer.mcapio.write.chunked_writer import ChunkedWriter
from analyzer.mcapio.write.message_writer import MessageWriter
from analyzer.protocol.types import CanFrame
from analyzer.tally import Tally

times = st.one_of(
    st.floats(min_value=1.7e9, max_value=1.8e9),  # Unix times, as most logs have
    st.floats(min_value=0.0, max_value=1e5),  # relative times, the fast path's lower edge
    st.floats(allow_nan=True, allow_infinity=True),  # anything else
)

frames = st.builds(
    CanFrame,
    time=times,
    can_id=st.integers(0, 0x1FFFFFFF),
    data=st.binary(max_size=64),
    extended=st.booleans(),
    channel=st.sampled_from(["", "can0", "vcan1", 'odd "name"']),
    is_remote=st.booleans(),
    is_error=st.booleans(),
    is_fd=st.booleans(),
    direction=st.sampled_from(["", "rx", "tx"]),
    remote_dlc=st.integers(0, 15),
)


def written(batch: list[CanFrame]) -> list[tuple[int, int, bytes]]:
    """(log time, sequence, data) of the /can/frames messages the writer puts in a file."""
    stream = io.BytesIO()
    writer = ChunkedWriter(stream, chunk_size=4096)
    writer.start()
    registry = ChannelRegistry(writer, default_schemas())
    MessageWriter(writer, registry, Tally(), None).write_items(batch)
    writer.finish()
    stream.seek(0)
    reader = make_reader(stream)
    return [
        (message.log_time, message.sequence, message.data)
        for _, channel, message in reader.iter_messages(log_time_order=False)
        if channel.topic == TOPIC_CAN_FRAMES
    ]


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(st.lists(frames, min_size=1, max_size=40))
def test_each_frame_is_written_as_can_frame_json_numbered_in_order(batch: list[CanFrame]) -> None:
    batch.sort(key=lambda f: time_ns(f.time))  # the file keeps log-time order
    messages = written(batch)
    assert [data for _, _, data in messages] == [can_frame_json(f) for f in batch]
    assert [number for _, number, _ in messages] == list(range(1, len(batch) + 1))
    assert [log_time for log_time, _, _ in messages] == [time_ns(f.time) for f in batch]


@settings(max_examples=500, deadline=None)
@given(st.floats(min_value=FLOAT_AS_REPR_FROM, max_value=1e16, exclude_max=True))
def test_orjson_writes_a_time_as_repr_does_where_the_writer_uses_it(t: float) -> None:
    assert orjson.dumps(t) == repr(t).encode()


def test_the_fast_path_starts_where_repr_stops_using_exponents() -> None:
    assert "e" not in repr(FLOAT_AS_REPR_FROM) and "e" in repr(math.nextafter(1e-4, 0))
