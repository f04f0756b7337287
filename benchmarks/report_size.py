"""Report size, memory and drawing time: a long dense flight against one a tenth as long.

    python benchmarks/report_size.py [--frames N] [--keep DIR]

Writes the dense bus mix of ``decode_speed.py`` (per 50 frames: a feedback message,
9 ``gimbal_control`` from a pilot's stick (smooth movements, speeds changing in every
command, zeros while centred), 5 GPS frames with moving positions, 32 foreign frames;
every value changing) at ``--frames`` (default 2,000,000)
and at a tenth of that, runs ``gimbal-analyzer report`` on each in its own process and
opens each page in headless Chromium. For each it prints the HTML's size, the report
process's peak memory, its CPU time, and the milliseconds the page took from the start
of loading to its plots drawn (``data-drawn-ms``, set by the page itself), with the
ratio of the long flight's figures to the short one's.

Targets for 2M frames: <= 10 MB of HTML, <= 150 MB peak memory, drawn in a few seconds.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.decode_speed import write_log  # noqa: E402

# The report in a fresh process; its own peak memory (VmHWM) on stderr.
CHILD = """
import sys
from analyzer.cli import main
code = main(["report", sys.argv[1], "-o", sys.argv[2], "--force"])
sys.stdout.flush()
peak = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")]
print(peak[0].strip() if peak else "VmHWM: 0 kB", file=sys.stderr)
sys.exit(code)
"""


def report(log: Path, page: Path) -> tuple[float, int]:
    """CPU seconds and peak memory (KiB) of ``report`` on ``log``."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    before = os.times()
    done = subprocess.run(
        [sys.executable, "-c", CHILD, str(log), str(page)], capture_output=True, env=env
    )
    after = os.times()
    if done.returncode != 0:
        raise SystemExit(f"report failed: {done.stderr.decode(errors='replace')[-2000:]}")
    seconds = after.children_user - before.children_user
    seconds += after.children_system - before.children_system
    return seconds, int(done.stderr.decode().split()[-2])


def drawn_ms(page: Path, profile: Path) -> int:
    """Milliseconds from loading to the plots drawn, best of three loads."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        raise SystemExit("chromium is not installed")
    best = None
    for _ in range(3):
        done = subprocess.run(
            [chromium, "--headless", "--no-sandbox", "--disable-gpu",
             f"--user-data-dir={profile}", "--dump-dom", page.as_uri()],
            capture_output=True, text=True, timeout=300, encoding="utf-8",
        )  # fmt: skip
        found = re.search(r'data-drawn-ms="(\d+)"', done.stdout)
        if not found:
            raise SystemExit(f"the page did not draw its plots: {done.stderr[-2000:]}")
        ms = int(found.group(1))
        best = ms if best is None else min(best, ms)
    assert best is not None
    return best


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--frames", type=int, default=2_000_000)
    parser.add_argument("--keep", metavar="DIR", help="write the logs and pages here")
    args = parser.parse_args()
    folder = Path(args.keep or tempfile.mkdtemp(prefix="report-size-"))
    folder.mkdir(parents=True, exist_ok=True)
    figures = {}
    for frames in (args.frames // 10, args.frames):
        log, page = folder / f"dense-{frames}.log", folder / f"dense-{frames}.html"
        print(f"writing {frames:,} frames ...", flush=True)
        write_log(log, frames, "dense")
        seconds, peak = report(log, page)
        ms = drawn_ms(page, folder / "chromium-profile")
        size = page.stat().st_size
        figures[frames] = (size, peak, seconds, ms)
        print(
            f"  {frames:>9,} frames: {size / 1024:8,.0f} KiB of HTML, peak memory "
            f"{peak / 1024:6.1f} MiB, {seconds:6.1f} s CPU, drawn {ms:,} ms after loading",
            flush=True,
        )
    (s1, p1, c1, m1), (s2, p2, c2, m2) = figures.values()
    print(
        f"ten times the flight: HTML x{s2 / s1:.2f}, memory x{p2 / p1:.2f}, "
        f"CPU x{c2 / c1:.2f}, drawing x{m2 / m1:.2f}"
    )
    big = figures[args.frames]
    print(
        f"targets at {args.frames:,} frames: HTML {big[0] / 1e6:.2f} MB <= 10 MB: "
        f"{'met' if big[0] <= 10e6 else 'MISSED'}; memory {big[1] / 1024:.0f} MiB <= 150 MB: "
        f"{'met' if big[1] * 1024 <= 150e6 else 'MISSED'}"
    )
    if not args.keep:
        shutil.rmtree(folder, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
