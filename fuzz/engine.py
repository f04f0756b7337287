"""One target fuzzed in this process by atheris (libFuzzer), with the crash rules as limits."""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

from fuzz.rules import HANG_S, MEMORY_MB
from fuzz.targets import Target

REPO = Path(__file__).resolve().parent.parent
REGRESSIONS = REPO / "fuzz" / "regressions"
# Coverage is measured in these packages: ours, and the libraries that parse inputs for
# us (python-can's log readers, dpkt's pcap, the MCAP and ROS bag readers).
INSTRUMENTED = ["analyzer", "can", "dpkt", "mcap", "mcap_ros2", "rosbags"]
# ... but not the modules that compare numpy arrays: atheris keeps the array each
# instrumented rich comparison returns (measured: a comparison of 10,000 values leaks
# 10 kB a call), so after some 50,000 inputs the process passes the memory rule by
# itself. Their code is array arithmetic with few branches; the per-frame code they
# hand the rest to is instrumented.
NOT_INSTRUMENTED = [
    "analyzer.analysis.motion_fit",
    "analyzer.analysis.stick_judge",
    "analyzer.feedback_track",
    "analyzer.fleet.arrow_arrays",
    "analyzer.fleet.column_builders",
    "analyzer.fleet.table_columns",
    "analyzer.inputs.blf.columns",
    "analyzer.inputs.candump.column_runs",
    "analyzer.inputs.candump.columns",
    "analyzer.protocol.arrays",
    "analyzer.protocol.event_columns",
    "analyzer.protocol.frame_columns",
    "analyzer.protocol.vector_decode",
    "analyzer.protocol.vector_layouts",
    "analyzer.tally",
]
MIN_MAX_LEN = 4096  # inputs up to this size at least (or the largest seed)


def write_seeds(target: Target, folder: Path) -> int:
    """The target's seeds as files in ``folder``; the size of the largest."""
    import hashlib

    folder.mkdir(parents=True, exist_ok=True)
    largest = 0
    for seed in target.seeds():
        (folder / hashlib.sha1(seed).hexdigest()).write_bytes(seed)
        largest = max(largest, len(seed))
    return largest


def libfuzzer_options(seconds: float, runs: int | None, max_len: int, work: Path) -> list[str]:
    """The crash rules as libFuzzer's limits, and where it keeps what it finds."""
    options = [
        f"-max_total_time={max(1, round(seconds))}",
        f"-timeout={round(HANG_S)}",
        f"-rss_limit_mb={MEMORY_MB}",
        f"-max_len={max(max_len, MIN_MAX_LEN)}",
        f"-artifact_prefix={work}/",
        "-print_final_stats=1",
    ]
    if runs is not None:
        options.append(f"-runs={runs}")
    return options


def fuzz(target: Target, seconds: float, work: Path, runs: int | None = None) -> None:
    """Fuzz ``target`` for ``seconds`` (libFuzzer exits the process at the end: exit 0,
    or non-zero with the input that crashed saved in ``work``). The corpus grows in
    ``work/corpus``; the seeds and the target's regression inputs start it."""
    try:
        import atheris
    except ImportError:
        raise SystemExit(
            "python -m fuzz: atheris is not installed (pip install -e '.[test,fuzz]')"
        ) from None

    corpus, seeds = work / "corpus", work / "seeds"
    corpus.mkdir(parents=True, exist_ok=True)
    with atheris.instrument_imports(include=INSTRUMENTED, exclude=NOT_INSTRUMENTED):
        # The API and what it imports are instrumented as they are imported.
        import analyzer.api.analysis
        import analyzer.api.reading  # noqa: F401

        largest = write_seeds(target, seeds)
        # Each seed once inside the instrumentation, so that the modules the target
        # imports on first use are instrumented too (what breaks is seen just below:
        # here atheris says on stderr what it instruments, which a command's rules see).
        for seed in sorted(seeds.iterdir()):
            with contextlib.suppress(Exception):
                target.run(seed.read_bytes())
    for seed in sorted(seeds.iterdir()):
        target.run(seed.read_bytes())  # a seed that crashes is a crash of its own
    folders = [corpus, seeds]
    regressions = REGRESSIONS / target.name
    if regressions.is_dir():
        folders.append(regressions)
    argv = [sys.argv[0], *libfuzzer_options(seconds, runs, largest, work)]
    atheris.Setup([*argv, *map(str, folders)], target.run)
    atheris.Fuzz()
