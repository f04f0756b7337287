"""Hour-long flights: CPU time and peak memory of analyze, convert, report and table.

    python benchmarks/long_flight.py [--frames 1000000] [--keep DIR] [--only analyze,convert]

Writes two candump -L logs of the dense bus mix of ``decode_speed.py`` (per 50 frames:
4 feedback segments of a gimbal whose attitude moves in every message, 9
``gimbal_control`` from a pilot's stick (smooth movements, speeds changing in every
command, zeros while centred), 5 GPS frames of a moving aircraft, 32 frames of 80
foreign IDs), of N and 2N frames (1M frames is about 42
minutes of that bus; 2M about an hour and a half), and runs each command on each in a
fresh process, measuring its CPU time (start-up included) and its peak memory (VmHWM):

    decode --json      the reference: decoding alone, every event printed
    analyze --json     the response analysis, every finding printed
    convert            the MCAP recording, /analysis/response included
    report             the HTML report
    table              the Parquet dataset (pyarrow loaded)

and prints, in the same run, the ratios the goals are about:

    analyze <= 3x and convert <= 4x decode's CPU time on the same file,
    2N frames <= 2.3x the time of N frames (time linear in the flight),
    peak memory at 2N frames <= 150 MB for analyze, convert, report and table.

Each command runs ``--repeat`` times per file (default 3), the commands alternating, and
the fastest run counts: on a shared machine a run is only ever slowed down by other work,
never sped up (the load average is printed with the figures). Two runs were not enough:
decode's own time moved by a fifth between them, and with it every ratio. Peak memory is the
largest of the runs. The package's bytecode is compiled first, as ``pip install`` does.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from decode_speed import compile_package, write_log  # noqa: E402

# Runs the command in this fresh process and reports its own peak memory (VmHWM counts
# only after exec; ru_maxrss would include the parent's pages at fork).
CHILD = """
import sys
from analyzer.cli import main
code = main(sys.argv[1:])
sys.stdout.flush()
peak = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")]
print(peak[0].strip(), file=sys.stderr)
sys.exit(code)
"""

COMMANDS = ("decode", "analyze", "convert", "report", "table")
LIMITS_MB = {"analyze": 150, "convert": 150, "report": 150, "table": 150}
RATIO_LIMITS = {"analyze": 3.0, "convert": 4.0}
GROWTH_LIMIT = 2.3


def arguments(command: str, log: Path, out: Path) -> list[str]:
    if command == "decode":
        return ["decode", str(log), "--json"]
    if command == "analyze":
        return ["analyze", str(log), "--json"]
    if command == "convert":
        return ["convert", str(log), "-o", str(out / "flight.mcap"), "--force", "-q"]
    if command == "report":
        return ["report", str(log), "-o", str(out / "flight.html"), "--force"]
    # A new dataset each run: table skips an input already in its dataset.
    dataset = out / f"fleet-{log.stem}"
    if dataset.exists():
        shutil.rmtree(dataset)
    return ["table", str(log), "-o", str(dataset), "--workers", "1", "-q"]


def run(command: str, log: Path, out: Path) -> tuple[float, float]:
    """CPU seconds (user + system) and peak memory in MB of one run in a fresh process."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    before = os.times()
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, *arguments(command, log, out)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=env,
        check=False,
    )
    after = os.times()
    seconds = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    err = proc.stderr.decode(errors="replace")
    if proc.returncode != 0:
        raise SystemExit(f"{command} failed on {log.name}:\n{err}")
    peak = next(line for line in err.splitlines() if line.startswith("VmHWM:"))
    return seconds, int(peak.split()[1]) / 1024


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--frames", type=int, default=1_000_000, help="N (default 1M)")
    parser.add_argument("--keep", metavar="DIR", help="write the logs here and keep them")
    parser.add_argument(
        "--only", default=",".join(COMMANDS[1:]), help="commands besides decode (comma-separated)"
    )
    parser.add_argument("--repeat", type=int, default=3, help="runs per command and file")
    args = parser.parse_args()
    wanted = ["decode", *[c for c in args.only.split(",") if c and c != "decode"]]
    for name in wanted:
        if name not in COMMANDS:
            parser.error(f"--only {name}: one of {', '.join(COMMANDS[1:])}")
    compile_package()
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(args.keep) if args.keep else Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        sizes = (args.frames, 2 * args.frames)
        logs = {}
        for n in sizes:
            log = folder / f"dense-{n}.log"
            if not log.exists():
                print(f"writing {n:,} frames of the dense mix ...", flush=True)
                write_log(log, n, "dense")
            logs[n] = log
        cpu: dict[tuple[str, int], float] = {}
        peak: dict[tuple[str, int], float] = {}
        for _ in range(max(1, args.repeat)):
            for n in sizes:
                for command in wanted:
                    seconds, mb = run(command, logs[n], Path(scratch))
                    key = (command, n)
                    cpu[key] = min(seconds, cpu.get(key, seconds))
                    peak[key] = max(mb, peak.get(key, mb))
                    print(
                        f"  {command:<8} {n:>10,} frames  {seconds:7.2f} s CPU  {mb:7.1f} MB peak"
                        f"  (load {os.getloadavg()[0]:.1f})",
                        flush=True,
                    )
    return report(wanted, sizes, cpu, peak)


def report(
    wanted: list[str],
    sizes: tuple[int, int],
    cpu: dict[tuple[str, int], float],
    peak: dict[tuple[str, int], float],
) -> int:
    small, big = sizes
    failed = 0
    print(f"\n{'command':<8} {'x decode':>16} {'2N / N time':>12} {'peak at 2N':>12}")
    for command in wanted:
        ratios = [cpu[command, n] / cpu["decode", n] for n in sizes]
        growth = cpu[command, big] / cpu[command, small]
        mb = peak[command, big]
        marks = []
        if command in RATIO_LIMITS and max(ratios) > RATIO_LIMITS[command]:
            marks.append(f"over {RATIO_LIMITS[command]:g}x decode")
        if growth > GROWTH_LIMIT:
            marks.append(f"grows more than {GROWTH_LIMIT:g}x")
        if command in LIMITS_MB and mb > LIMITS_MB[command]:
            marks.append(f"over {LIMITS_MB[command]} MB")
        failed += bool(marks)
        print(
            f"{command:<8} {ratios[0]:6.2f}x / {ratios[1]:5.2f}x {growth:11.2f}x {mb:9.1f} MB"
            + (f"   MISSED: {', '.join(marks)}" if marks else "")
        )
    print("(x decode at N / at 2N frames; goals: analyze <= 3x, convert <= 4x decode's CPU,")
    print(f" 2N <= {GROWTH_LIMIT}x N, peak <= 150 MB)")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
