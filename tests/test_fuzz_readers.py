"""Mutation fuzzing of every reader: damaged files end as exit 0 with diagnostics, or as
exit 2 with one line; never a traceback.

Each seed file is written the way the real tool writes it; every mutant is made from a
seeded random generator (bit flips, overwritten and cut ranges, duplicated and deleted
slices, size fields set to extremes, files spliced together, mangled text lines) and
decoded in-process by ``gimbal-analyzer decode``: by its name, with its right
``--format`` and with a wrong one. The mutants are taken round-robin over the seeds until
the count or the time budget runs out (``GIMBAL_FUZZ_MUTANTS``, ``GIMBAL_FUZZ_SECONDS``;
``GIMBAL_FUZZ_SEED`` picks another series). A failure names the mutant, and the file is
kept to reproduce it with ``python -m analyzer decode FILE``.
"""

from __future__ import annotations

import faulthandler
import gzip
import os
import random
import time
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import pytest

from analyzer.inputs import FORMATS
from fuzz.rules import one_error_line, run_cli
from fuzz.seeds import FRAMES, Seed, make_seeds, python_can_bytes, seed_frames
from tests.log_makers import savvycan_csv

SEED = int(os.environ.get("GIMBAL_FUZZ_SEED", "28"))
MUTANTS = int(os.environ.get("GIMBAL_FUZZ_MUTANTS", "1500"))
BUDGET_S = float(os.environ.get("GIMBAL_FUZZ_SECONDS", "25"))
HANG_S = 60.0  # one mutant decoding longer than this is a hang (see _fuzz)
TEXT_FORMATS = frozenset({"candump", "asc", "trc", "csv", "savvycan"})
# Values a damaged size or count field takes: zero, small, the edges of signed and
# unsigned 16/32/64-bit integers.
EXTREMES = (
    b"\x00\x00\x00\x00",
    b"\x01\x00\x00\x00",
    b"\xff\xff\xff\xff",
    b"\xff\xff\xff\x7f",
    b"\x00\x00\x00\x80",
    b"\xff\xff",
    b"\xff\xff\xff\xff\xff\xff\xff\x7f",
    b"\x00\x00\x00\xa0",  # 2.7 GB
)
TEXT_NOISE = ("-1", "nan", "1e309", "99999999999999999999", "", "#", "\x00", "é", "0x", ";")


# -- mutators: (rng, data, another seed's data) -> mutated data, what was done ---------------

Mutator = Callable[[random.Random, bytes, bytes], tuple[bytes, str]]


def _span(rng: random.Random, data: bytes, most: int = 64) -> tuple[int, int]:
    start = rng.randrange(len(data))
    return start, min(len(data), start + rng.randint(1, most))


def flip_bits(rng: random.Random, data: bytes, _: bytes) -> tuple[bytes, str]:
    out = bytearray(data)
    where = sorted(rng.randrange(len(out) * 8) for _ in range(rng.randint(1, 8)))
    for bit in where:
        out[bit // 8] ^= 1 << (bit % 8)
    return bytes(out), f"flip bits {where}"


def overwrite(rng: random.Random, data: bytes, _: bytes) -> tuple[bytes, str]:
    start, end = _span(rng, data)
    fill = rng.choice([b"\0", b"\xff", None])
    new = fill * (end - start) if fill else rng.randbytes(end - start)
    return data[:start] + new + data[end:], f"overwrite [{start}:{end}] with {new[:8].hex()}"


def extreme_field(rng: random.Random, data: bytes, _: bytes) -> tuple[bytes, str]:
    value = rng.choice(EXTREMES)
    start = rng.randrange(0, max(1, len(data) - len(value)), rng.choice([1, 2, 4]))
    return data[:start] + value + data[start + len(value) :], f"{value.hex()} at {start}"


def cut(rng: random.Random, data: bytes, _: bytes) -> tuple[bytes, str]:
    at = rng.randrange(len(data))
    return data[:at], f"cut at {at}"


def delete_slice(rng: random.Random, data: bytes, _: bytes) -> tuple[bytes, str]:
    start, end = _span(rng, data, 512)
    return data[:start] + data[end:], f"delete [{start}:{end}]"


def duplicate_slice(rng: random.Random, data: bytes, _: bytes) -> tuple[bytes, str]:
    start, end = _span(rng, data, 512)
    at = rng.randrange(len(data))
    return data[:at] + data[start:end] + data[at:], f"copy [{start}:{end}] to {at}"


def splice(rng: random.Random, data: bytes, other: bytes) -> tuple[bytes, str]:
    at, there = rng.randrange(len(data)), rng.randrange(len(other))
    return data[:at] + other[there:], f"head [:{at}] + another file from {there}"


def mangle_line(rng: random.Random, data: bytes, _: bytes) -> tuple[bytes, str]:
    """A text line damaged the ways an editor, a serial console or a disk does."""
    lines = data.split(b"\n")
    index = rng.randrange(len(lines))
    line = lines[index].decode("latin-1")
    fields = line.replace(",", " ").split()
    how = rng.randrange(6)
    if how == 0 and fields:  # a field replaced by noise
        word = rng.choice(fields)
        line = line.replace(word, rng.choice(TEXT_NOISE), 1)
    elif how == 1 and fields:  # a field dropped
        line = line.replace(rng.choice(fields), "", 1)
    elif how == 2:  # cut inside the line
        line = line[: rng.randrange(len(line) + 1)]
    elif how == 3:  # characters inserted
        at = rng.randrange(len(line) + 1)
        line = line[:at] + rng.choice(TEXT_NOISE) * rng.randint(1, 3) + line[at:]
    elif how == 4:  # a very long line
        line = line + "A" * rng.choice([300, 70_000])
    else:  # two lines swapped
        other = rng.randrange(len(lines))
        lines[other], line = line.encode("latin-1"), lines[other].decode("latin-1")
    lines[index] = line.encode("latin-1")
    return b"\n".join(lines), f"line {index + 1}: way {how}"


BINARY: tuple[Mutator, ...] = (
    flip_bits,
    overwrite,
    extreme_field,
    cut,
    delete_slice,
    duplicate_slice,
    splice,
)


@dataclass(frozen=True)
class Mutant:
    name: str
    data: bytes
    fmt: str | None  # None: from the name and content
    what: str


def _gunzipped_text(seed: Seed) -> bool:
    return seed.name.endswith(".gz") and seed.fmt in TEXT_FORMATS


def mutants(seeds: list[Seed], rng: random.Random) -> Iterator[Mutant]:
    """Round-robin over the seeds, for ever: one mutant of each seed in turn."""
    wrong = list(FORMATS)
    count = 0
    while True:
        for seed in seeds:
            count += 1
            data = seed.data
            text = seed.fmt in TEXT_FORMATS
            if _gunzipped_text(seed) and rng.random() < 0.5:
                data = gzip.decompress(data)  # the text damaged, then compressed again
                mutated, what = mangle_line(rng, data, b"")
                mutated, what = gzip.compress(mutated), f"gzip of {what}"
            elif text and not seed.name.endswith(".gz") and rng.random() < 0.5:
                mutated, what = mangle_line(rng, data, b"")
            else:
                mutator = rng.choice(BINARY)
                other = rng.choice(seeds).data
                mutated, what = mutator(rng, data, other)
                for _ in range(rng.choice([0, 0, 0, 1, 2])):  # sometimes several at once
                    mutator = rng.choice(BINARY)
                    mutated, more = mutator(rng, mutated or b"\0", other)
                    what += f"; {more}"
            way = count % 3
            fmt = None if way == 0 else seed.fmt if way == 1 else rng.choice(wrong)
            yield Mutant(seed.name, mutated, fmt, f"{seed.name} {what}")


def decode(path: Path, fmt: str | None, *, stdin: bool = False) -> tuple[int, str, str]:
    """``gimbal-analyzer decode`` in this process: (exit code, stdout, stderr); with
    ``stdin`` the file is piped in (``decode -``)."""
    args = ["decode", "-" if stdin else str(path)] + (["--format", fmt] if fmt else [])
    return run_cli(args, path.read_bytes() if stdin else b"")


def _one_error(code: int, err: str) -> bool:
    return one_error_line("decode", code, err)


@pytest.fixture(scope="module")
def seeds(tmp_path_factory: pytest.TempPathFactory) -> list[Seed]:
    return make_seeds(tmp_path_factory.mktemp("seeds"))


def test_every_seed_decodes_cleanly(seeds: list[Seed], tmp_path: Path) -> None:
    """The unmutated files are read with their formats (else the fuzzing tests nothing)."""
    assert {seed.fmt for seed in seeds} == set(FORMATS)
    for seed in seeds:
        path = tmp_path / seed.name
        path.write_bytes(seed.data)
        code, out, err = decode(path, None)
        assert code == 0, f"{seed.name}: {err}"
        assert "/gimbal/" in out, seed.name


@pytest.mark.slow
def test_mutants_of_every_reader_never_raise(seeds: list[Seed], tmp_path: Path) -> None:
    rng = random.Random(SEED)
    tried: dict[str, int] = {}
    failures: list[str] = []
    with (tmp_path / "hang-traceback.txt").open("w", encoding="utf-8") as dump:
        try:
            _fuzz(seeds, rng, tmp_path, dump, tried, failures)
        finally:
            faulthandler.cancel_dump_traceback_later()
    assert not failures, f"{len(failures)} mutant(s) failed:\n" + "\n".join(failures[:10])
    assert set(tried) == {seed.name for seed in seeds}  # the budget reached every reader


def _fuzz(
    seeds: list[Seed],
    rng: random.Random,
    tmp_path: Path,
    dump: IO[str],
    tried: dict[str, int],
    failures: list[str],
) -> None:
    """Decode mutants until the count or the time budget runs out. A mutant that hangs
    ends the test run after HANG_S (a hang must not stall the suite): its name is in
    ``current-mutant.txt`` and every thread's traceback in ``hang-traceback.txt`` of
    the test's folder (pytest's captured output is lost with the process)."""
    start = time.monotonic()
    current = tmp_path / "current-mutant.txt"
    for number, mutant in enumerate(mutants(seeds, rng)):
        if number >= MUTANTS or time.monotonic() - start > BUDGET_S:
            break
        folder = tmp_path / f"m{number:04d}"
        folder.mkdir()
        path = folder / mutant.name
        path.write_bytes(mutant.data)
        # Text and raw streams also come through a pipe, read by the standard-input readers.
        piped = mutant.fmt in ("candump", "stream") and number % 2 == 0
        label = f"#{number} {mutant.what} --format {mutant.fmt}" + (" < stdin" if piped else "")
        current.write_text(f"{label}: {path}\n", encoding="utf-8")
        faulthandler.dump_traceback_later(HANG_S, exit=True, file=dump)
        try:
            code, _, err = decode(path, mutant.fmt, stdin=piped)
        except Exception:  # a traceback: what this test looks for
            failures.append(f"{label}: {path}\n{traceback.format_exc(limit=-4)}")
            continue
        finally:
            tried[mutant.name] = tried.get(mutant.name, 0) + 1
        if code not in (0, 2) or not _one_error(code, err):
            failures.append(f"{label}: {path}\nexit {code}: {err[-2000:]}")
        elif code == 0:
            (folder / mutant.name).unlink()  # keep only the files that failed


# -- what the fuzzing found, one test each ------------------------------------------------------


def _bad_lines(path: Path, fmt: str) -> tuple[int, list[str], str]:
    code, out, err = decode(path, fmt)
    return code, [line for line in out.splitlines() if "BAD_LINE" in line], err


def test_a_savvycan_time_beyond_any_date_is_a_bad_line(tmp_path: Path) -> None:
    lines = savvycan_csv(seed_frames()[:3]).splitlines()
    lines[2] = "99999999999999999999999999" + lines[2][lines[2].index(",") :]
    path = tmp_path / "gvret.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    code, bad, err = _bad_lines(path, "savvycan")
    assert code == 0, err
    assert len(bad) == 1 and "line 3" in bad[0] and "is out of range" in bad[0]


@pytest.mark.parametrize(("name", "fmt"), [("x.trc", "trc"), ("x.csv", "csv")])
def test_a_python_can_time_of_infinity_is_a_bad_line(tmp_path: Path, name: str, fmt: str) -> None:
    frames = seed_frames()[:3]
    text = python_can_bytes(tmp_path, name, frames).decode()
    stamp = {"trc": f"{(frames[1].time - frames[0].time) * 1000:.1f}"}
    old = stamp.get(fmt, str(frames[1].time))
    assert old in text
    (tmp_path / name).write_text(
        text.replace(old, "1e309", 1), encoding="utf-8"
    )  # python-can reads inf
    code, bad, err = _bad_lines(tmp_path / name, fmt)
    assert code == 0, err
    assert len(bad) == 1 and "inf s is out of range" in bad[0]


def test_a_line_python_can_skips_with_a_warning_is_a_bad_line_not_a_stderr_message(
    tmp_path: Path,
) -> None:
    text = python_can_bytes(tmp_path, "x.trc", seed_frames()[:3]).decode().splitlines()
    last = len(text)
    text.append("      4")  # a message number and nothing else: python-can logs and skips it
    (tmp_path / "x.trc").write_text("\n".join(text) + "\n", encoding="utf-8")
    code, bad, err = _bad_lines(tmp_path / "x.trc", "trc")
    assert code == 0 and err == ""
    assert len(bad) == 1 and f"line {last + 1}: can: TRCReader: Failed to parse" in bad[0]


def test_an_mf4_that_asammdf_cannot_open_is_one_line_without_a_cleanup_traceback(
    tmp_path: Path,
) -> None:
    import gc

    data = python_can_bytes(tmp_path, "x.mf4", seed_frames())
    path = tmp_path / "cut.mf4"
    path.write_bytes(data[:1000])
    code, _, err = decode(path, None)
    gc.collect()  # asammdf's half-made reader is cleaned up: its __del__ fails
    assert code == 2
    assert err.startswith("gimbal-analyzer decode: error: cannot read") and err.count("\n") == 1


def test_an_mf4_data_group_whose_records_are_not_counted_is_refused_not_looped_on(
    tmp_path: Path,
) -> None:
    import struct

    data = bytearray(python_can_bytes(tmp_path, "x.mf4", seed_frames()))
    cycles_at = _channel_group_data(data) + 8  # the CAN frames' group, after cg_record_id
    assert struct.unpack_from("<Q", data, cycles_at)[0] == FRAMES
    struct.pack_into("<Q", data, cycles_at, 0)  # asammdf loops for ever on this
    path = tmp_path / "uncounted.mf4"
    path.write_bytes(bytes(data))
    code, _, err = decode(path, None)
    assert code == 2
    assert "holds data but counts no record" in err and err.count("\n") == 1


REGRESSIONS = Path(__file__).resolve().parent.parent / "fuzz" / "regressions"


def _channel_group_data(data: bytes | bytearray) -> int:
    """Where the data part of an MF4 file's first channel group (python-can's CAN frames:
    40 records) starts: after its header and its links."""
    import struct

    group = data.find(b"##CG")
    links = struct.unpack_from("<Q", data, group + 16)[0]
    return group + 24 + 8 * links


@pytest.mark.parametrize(
    ("name", "why"),
    [
        # python-can 4.6.1 loops on each of these for ever: warning each time, ...
        ("object-of-size-0-unknown-header-version.blf", "which Vector does not document"),
        ("object-of-size-0-can-message.blf", "with a size of 0 bytes"),  # ... the same frame
        ("object-of-size-0-unknown-type.blf", "with a size of 0 bytes"),  # ... silently
    ],
)
def test_a_blf_object_whose_size_is_0_is_skipped_with_a_diagnostic(name: str, why: str) -> None:
    code, out, err = decode(REGRESSIONS / "blf" / name, "blf")
    assert code == 0 and err == ""
    skipped = [line for line in out.splitlines() if "BAD_FRAME" in line and "skipped" in line]
    assert skipped and all(why in line for line in skipped)


def test_an_asc_line_of_control_characters_is_a_bad_line() -> None:
    code, bad, err = _bad_lines(REGRESSIONS / "asc" / "control-character-line.asc", "asc")
    assert code == 0 and err == ""
    assert "line 1: " in bad[0] and "a line of control characters" in bad[0]


def test_an_mf4_channel_outside_its_record_is_refused_before_asammdf_reads_it() -> None:
    """asammdf would read outside its buffer and crash the process (SIGSEGV)."""
    code, _, err = decode(REGRESSIONS / "mf4" / "channel-outside-its-record.mf4", None)
    assert code == 2 and err.count("\n") == 1
    assert "ends at byte 1,143,153,499 of a record of 84 bytes" in err


def test_an_mf4_record_size_of_a_gigabyte_is_refused_before_asammdf_allocates_it() -> None:
    """Found by the fuzzer: 8,488 bytes made asammdf allocate one record of 944 MB."""
    code, _, err = decode(REGRESSIONS / "mf4" / "record-of-944-mb.mf4", None)
    assert code == 2 and err.count("\n") == 1
    assert "has records of 944,329,507 bytes, more than a CAN bus-logging record" in err


@pytest.mark.parametrize(("field", "value"), [(0, 3 << 28), (4, 1 << 30), (0, (1 << 20) + 1)])
def test_an_mf4_record_size_field_beyond_any_can_record_is_refused(
    tmp_path: Path, field: int, value: int
) -> None:
    """cg_data_bytes (field 0) or cg_inval_bytes (field 4) of the CAN frames' group."""
    import struct

    data = bytearray(python_can_bytes(tmp_path, "x.mf4", seed_frames()))
    data_bytes_at = _channel_group_data(data) + 8 + 8 + 2 + 2 + 4  # after the cycle count
    record = struct.unpack_from("<I", data, data_bytes_at)[0]
    assert 0 < record < 200  # a bus-logging record as python-can writes it
    struct.pack_into("<I", data, data_bytes_at + field, value)
    path = tmp_path / "huge-record.mf4"
    path.write_bytes(bytes(data))
    code, _, err = decode(path, None)
    assert code == 2 and err.count("\n") == 1
    assert "more than a CAN bus-logging record holds" in err


def test_an_mf4_whose_chain_of_groups_loops_is_refused_not_followed_for_ever() -> None:
    """Found by the fuzzer: asammdf counts the channel groups by following raw links."""
    code, _, err = decode(REGRESSIONS / "mf4" / "chain-of-groups-that-loops.mf4", None)
    assert code == 2 and err.count("\n") == 1
    assert "its chain of data groups comes back to byte 1,000" in err


def test_an_mf4_channel_behind_a_damaged_link_count_is_checked_as_asammdf_reads_it() -> None:
    """Found by the fuzzer next: a channel block of the standard length whose link count
    is damaged; asammdf reads it at its fixed layout and crashed on its sub-channel."""
    code, _, err = decode(REGRESSIONS / "mf4" / "channel-with-damaged-link-count.mf4", None)
    assert code == 2 and err.count("\n") == 1
    assert "its channel at byte 1,960 ends at byte 32,781 of a record of 84 bytes" in err


def test_an_mf4_whose_channel_groups_loop_behind_a_damaged_header_is_refused() -> None:
    """Found by the fuzzer next: the header block's link count damaged, a channel group
    linked to itself."""
    code, _, err = decode(REGRESSIONS / "mf4" / "chain-of-channel-groups-that-loops.mf4", None)
    assert code == 2 and err.count("\n") == 1
    assert "its chain of channel groups comes back to byte 3,936" in err


@pytest.mark.parametrize(("kind", "what"), [(b"##DG", "data groups"), (b"##CG", "channel groups")])
def test_an_mf4_group_linked_back_to_itself_is_refused(
    tmp_path: Path, kind: bytes, what: str
) -> None:
    """A data group's (or channel group's) next link pointing at the group itself."""
    import struct

    data = bytearray(python_can_bytes(tmp_path, "x.mf4", seed_frames()))
    group = data.find(kind)
    struct.pack_into("<Q", data, group + 24, group)  # its first link: the next group
    path = tmp_path / "looping.mf4"
    path.write_bytes(bytes(data))
    code, _, err = decode(path, None)
    assert code == 2 and err.count("\n") == 1
    assert f"its chain of {what} comes back to byte {group:,}" in err


def test_a_db3_message_whose_time_sqlite_holds_as_text_is_a_bad_frame() -> None:
    """sqlite3 keeps any type in any column: the message is skipped in words and the
    reading goes on (here up to a page the same damage broke: it says so)."""
    code, out, err = decode(REGRESSIONS / "ros2-db3" / "time-stored-as-text.db3", "rosbag")
    assert code == 0 and err == ""
    assert "message not read as a CAN frame: its time '' is no nanoseconds" in out
    assert "/uav/gps" in out and "cannot be read further" in out and "30 frames read" in out
