"""The fuzz targets by name: what each feeds its input to, and the seeds it starts from."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

from fuzz import decoder, files, live, video

ALL = "all"  # every target in one run: an input's first byte says whose it is


@dataclass(frozen=True)
class Target:
    """A fuzz target: ``run`` takes one input and raises on a crash (see fuzz.rules);
    ``seeds`` makes its starting corpus from the samples."""

    name: str
    what: str
    run: Callable[[bytes], None]
    seeds: Callable[[], list[bytes]]


def _file_targets() -> list[Target]:
    return [
        Target(
            spec.target,
            f"{spec.what}: read, analyze and decode of a {spec.name} file",
            files.file_runner(spec),
            files.file_seeds(spec),
        )
        for spec in files.FILE_FORMATS
    ]


@functools.cache
def targets() -> dict[str, Target]:
    """Every target, by name (``all`` last)."""
    found = [
        Target(
            "decoder",
            "the sans-IO Decoder: CAN frames, stream bytes and time, then analyze",
            decoder.run,
            decoder.seeds,
        ),
        *_file_targets(),
        Target(
            "tcp-client",
            "record / monitor --source tcp: what the IDU sends",
            live.run_client,
            live.seeds_client,
        ),
        Target(
            "tcp-proxy",
            "record / monitor --source proxy: what ground station and IDU send",
            live.run_proxy,
            live.seeds_proxy,
        ),
        Target(
            "video",
            "a recording whose video frames are the input: info, analyze, report",
            video.run,
            video.seeds,
        ),
    ]
    named = {target.name: target for target in found}
    parts = list(named.values())
    named[ALL] = Target(
        ALL,
        "every target at once: the first byte picks one, the rest is its input",
        functools.partial(_run_any, parts),
        functools.partial(_seeds_of_all, parts),
    )
    return named


def _run_any(parts: list[Target], data: bytes) -> None:
    if data:
        parts[data[0] % len(parts)].run(data[1:])


def _seeds_of_all(parts: list[Target]) -> list[bytes]:
    return [bytes([index]) + seed for index, part in enumerate(parts) for seed in part.seeds()]


def of_all(data: bytes) -> tuple[Target, bytes]:
    """The target an input of ``all`` goes to, and its own input."""
    parts = [target for name, target in targets().items() if name != ALL]
    return parts[data[0] % len(parts)], data[1:]
