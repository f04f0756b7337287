"""The video target: a recording whose camera frames hold the input's bytes.

A template recording is made once per run as ``demo --video`` makes it (the simulated
gimbal and camera in virtual time, a zoom command to judge from the picture). Each
input replaces its video frames' payloads: the input is a run of records, 2 bytes
little-endian of length and that many bytes, one per frame (fewer records, fewer
frames). The copy is then read as users read recordings: ``info`` (the streams, their
codec and size), ``analyze`` (camera commands judged from the picture, by PyAV and
OpenCV) and ``report`` (its camera section); each must keep the command line's rules.
"""

from __future__ import annotations

import base64
import functools
import json
import struct
from collections.abc import Iterator
from pathlib import Path

from fuzz.files import scratch
from fuzz.rules import cli, library

SIZE = (256, 144)  # the template's picture: large enough for the picture's judgement
FPS = 5
DURATION_S = 3.0
_LENGTH = struct.Struct("<H")


@functools.cache
def template() -> Path:
    """The recording whose video the inputs replace (made once per process)."""
    from analyzer.sim.camera.offline import record_offline
    from analyzer.sim.engine import SimConfig
    from analyzer.sim.ground import Step

    path = scratch() / "video-template.mcap"
    steps = (Step(0.2, "zoom", {"action": "zoom_in_2x"}),)
    config = SimConfig(ranging=False, uav=False)
    record_offline(path, steps, DURATION_S, config, size=SIZE, fps=FPS, gop_s=1.0)
    return path


def payloads(data: bytes) -> Iterator[bytes]:
    """The frames' payloads an input holds."""
    at = 0
    while at + _LENGTH.size <= len(data):
        (size,) = _LENGTH.unpack_from(data, at)
        at += _LENGTH.size
        yield data[at : at + size]
        at += size


def _is_video(schema_name: str) -> bool:
    from analyzer.mcapio.write.video import COMPRESSED_VIDEO

    return schema_name == COMPRESSED_VIDEO


def with_video(source: Path, target: Path, frames: Iterator[bytes]) -> None:
    """``source`` copied to ``target`` with its video frames' data taken from ``frames``."""
    from mcap.reader import make_reader
    from mcap.writer import Writer

    with source.open("rb") as inp, target.open("wb") as out:
        reader = make_reader(inp)
        header = reader.get_header()
        writer = Writer(out)
        writer.start(header.profile, header.library)
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema is not None and schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(
                    schema.name, schema.encoding, schema.data
                )
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(
                    channel.topic,
                    channel.message_encoding,
                    schemas.get(channel.schema_id, 0),
                    dict(channel.metadata),
                )
            data = message.data
            if schema is not None and _is_video(schema.name):
                payload = next(frames, None)
                if payload is None:
                    continue
                fields = json.loads(data)
                fields["data"] = base64.b64encode(payload).decode()
                data = json.dumps(fields).encode()
            writer.add_message(channels[channel.id], message.log_time, data, message.publish_time)
        for metadata in reader.iter_metadata():
            writer.add_metadata(metadata.name, dict(metadata.metadata))
        writer.finish()


def run(data: bytes) -> None:
    """The input's frames in a recording, read by ``info``, ``analyze`` and ``report``."""
    from analyzer.api.analysis import analyze

    path = scratch() / "video.mcap"
    with_video(template(), path, payloads(data))
    cli(["info", str(path)])
    library(lambda: list(analyze(path)))
    cli(["report", str(path), "-o", str(scratch() / "video.html"), "-f", "-q"])


def seeds() -> list[bytes]:
    """The template's own frames; its first second alone."""
    from mcap.reader import make_reader

    frames: list[bytes] = []
    with template().open("rb") as handle:
        for schema, _, message in make_reader(handle).iter_messages():
            if schema is not None and _is_video(schema.name):
                frames.append(base64.b64decode(json.loads(message.data)["data"]))
    whole = b"".join(_LENGTH.pack(len(frame)) + frame for frame in frames)
    first = b"".join(_LENGTH.pack(len(frame)) + frame for frame in frames[:FPS])
    return [whole, first]
