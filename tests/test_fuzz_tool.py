"""The fuzzing tool itself: how its targets read an input, and what it reports of a run."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from fuzz.decoder import ANY_CAN, CAN, STREAM, script_of, steps
from fuzz.figures import parse, table
from fuzz.live import split
from fuzz.seeds import SAMPLES, seed_frames
from fuzz.video import _LENGTH, payloads


def test_a_script_made_of_frames_feeds_those_frames_and_that_stream() -> None:
    frames = seed_frames()
    stream = (SAMPLES / "uart-dump.bin").read_bytes()
    fed = [s for s in steps(script_of(frames, stream)) if s.kind != 3]
    can = [s for s in fed if s.kind in (CAN, ANY_CAN)]
    assert [(s.can_id, s.data) for s in can] == [(f.can_id, f.data) for f in frames]
    assert b"".join(s.data for s in fed if s.kind == STREAM) == stream


@given(st.binary(max_size=2000))
def test_any_bytes_are_a_script(script: bytes) -> None:
    for step in steps(script):
        assert len(step.data) <= max(64, len(script))


@given(st.binary(max_size=300))
def test_a_proxy_input_is_split_without_losing_a_byte(data: bytes) -> None:
    to_idu, to_gs = split(data)
    assert to_idu + to_gs == data[2:] or (len(data) < 2 and to_gs == data)


def test_the_video_input_is_a_run_of_length_prefixed_frames() -> None:
    frames = [b"\x00\x00\x00\x01\x67", b"", b"x" * 300]
    data = b"".join(_LENGTH.pack(len(f)) + f for f in frames)
    assert list(payloads(data)) == frames
    assert list(payloads(data + b"\x05")) == frames  # a cut length is no frame


LOG = """\
INFO: Seed: 1
#2\tINITED cov: 356 ft: 356 corp: 1/720b exec/s: 0 rss: 201Mb
#4096\tpulse  cov: 540 ft: 1000 corp: 30/7000b lim: 720 exec/s: 400 rss: 201Mb
#16100\tDONE   cov: 574 ft: 1355 corp: 42/15126b lim: 729 exec/s: 519 rss: 201Mb
Done 16100 runs in 31 second(s)
stat::number_of_executed_units: 16100
stat::average_exec_per_sec:     519
stat::new_units_added:          127
stat::slowest_unit_time_sec:    0
stat::peak_rss_mb:              201
"""


def test_a_run_s_figures_come_from_libfuzzer_s_own_lines() -> None:
    figures = parse("blf", LOG)
    assert (figures.executions, figures.seconds, figures.exec_per_s) == (16100, 31, 519)
    assert (figures.coverage_start, figures.coverage, figures.corpus) == (356, 574, 42)
    assert figures.peak_rss_mb == 201 and figures.ok
    lines = table([figures], markdown=True).splitlines()
    assert lines[0].startswith("| target | executions") and lines[1].startswith("|---")
    assert lines[2] == "| blf | 16,100 | 519 | 356 -> 574 | 42 | 201 MB | nothing |"
