"""The columnar path against python-can, can-utils' log2asc and today's frame-by-frame path.

    python benchmarks/columnar_speed.py [--frames N] [--repeat N] [--log2asc PATH]
                                        [--table] [--keep DIR]

Writes the dense and random-ids candump logs of ``decode_speed.py`` (values change in
every frame: a moving gimbal, a pilot's stick, moving GPS; 36 % gimbal and UAV frames,
80 foreign IDs or a new foreign ID in every foreign frame), then measures in one run,
as CPU time of a fresh process (start-up included), best of ``--repeat``:

- python-can's ``can.LogReader`` iterating the file (no decoding);
- can-utils' ``log2asc`` converting it to ASC (C; found on PATH or given with
  ``--log2asc``; built from can-utils' source, it is not part of this project);
- ``decode --summary`` and ``decode --json`` frame by frame (``GIMBAL_ANALYZER_COLUMNAR=0``,
  the path before the columnar one) and columnar (the default), with peak memory;
- with ``--table``: ``table`` of a 2M-frame dense log, both paths.

Prints one table with every figure side by side and the goals of the columnar path.
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
sys.path.insert(0, str(ROOT))

from benchmarks.decode_speed import compile_package, write_log  # noqa: E402

# Peak memory (VmHWM) of the child, printed on stderr after the command's own output.
CHILD = """
import sys
from analyzer.cli import main
code = main(sys.argv[1:])
sys.stdout.flush()
peak = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")]
print(peak[0].strip() if peak else "VmHWM: 0 kB", file=sys.stderr)
sys.exit(code)
"""
PYTHON_CAN = """
import sys, can
n = 0
for _ in can.LogReader(sys.argv[1]):
    n += 1
print(n)
"""


def cpu(command: list[str], env: dict[str, str] | None = None) -> tuple[float, int]:
    """CPU seconds of a child process and its peak memory in KiB (0 when not printed)."""
    before = os.times()
    proc = subprocess.run(command, capture_output=True, env=env, check=False)
    after = os.times()
    if proc.returncode != 0:
        raise SystemExit(f"{command[:3]} failed: {proc.stderr.decode(errors='replace')[-400:]}")
    seconds = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    words = proc.stderr.decode(errors="replace").split()
    peak = int(words[-2]) if len(words) >= 2 and words[-1] == "kB" else 0
    return seconds, peak


def best(command: list[str], repeat: int, env: dict[str, str] | None = None) -> tuple[float, int]:
    runs = [cpu(command, env) for _ in range(repeat)]
    return min(r[0] for r in runs), max(r[1] for r in runs)


def ours(args: list[str], columnar: bool) -> tuple[list[str], dict[str, str]]:
    env = {
        **os.environ,
        "PYTHONPATH": str(ROOT),
        "GIMBAL_ANALYZER_COLUMNAR": "1" if columnar else "0",
    }
    return [sys.executable, "-c", CHILD, *args], env


def measure_log(path: Path, log2asc: str | None, repeat: int) -> dict[str, tuple[float, int]]:
    out: dict[str, tuple[float, int]] = {}
    out["python-can LogReader"] = best([sys.executable, "-c", PYTHON_CAN, str(path)], repeat)
    if log2asc:
        out["log2asc"] = best([log2asc, "-I", str(path), "-O", os.devnull, "can0"], repeat)
    for what, options in (("--summary", ["--summary"]), ("--json", ["--json"])):
        for columnar in (False, True):
            command, env = ours(["decode", *options, str(path)], columnar)
            if what == "--json":
                command = ["sh", "-c", '"$@" > /dev/null', "sh", *command]
            name = f"decode {what} ({'columnar' if columnar else 'today'})"
            out[name] = best(command, repeat, env)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--frames", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3, help="runs of each; the fastest counts")
    parser.add_argument("--log2asc", help="can-utils' log2asc (default: the one on PATH)")
    parser.add_argument("--table", action="store_true", help="also `table` of 2x --frames")
    parser.add_argument("--keep", metavar="DIR", help="write the logs here and keep them")
    args = parser.parse_args()
    log2asc = args.log2asc or shutil.which("log2asc")
    if not log2asc:
        print("log2asc not found (not on PATH, no --log2asc): its column is left out")
    compile_package()
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(args.keep or scratch)
        folder.mkdir(parents=True, exist_ok=True)
        results: dict[str, dict[str, tuple[float, int]]] = {}
        for mix in ("dense", "random-ids"):
            path = folder / f"columnar-{mix}.log"
            if not path.exists():
                print(f"writing {args.frames:,} frames of the {mix} mix ...", flush=True)
                write_log(path, args.frames, mix)
            results[mix] = measure_log(path, log2asc if mix == "dense" else None, args.repeat)
        if args.table:
            path = folder / "columnar-dense-2x.log"
            if not path.exists():
                write_log(path, 2 * args.frames, "dense")
            for columnar in (False, True):
                command, env = ours(
                    ["table", str(path), "-o", str(folder / f"fleet-{columnar}"), "-f"], columnar
                )
                results.setdefault("table", {})[
                    f"table ({'columnar' if columnar else 'today'})"
                ] = best(command, args.repeat, env)
    print()
    print(f"load: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} (1 and 5 minutes)")
    for mix, figures in results.items():
        print(f"\n[{mix}]  CPU s (best of {args.repeat}), peak memory")
        for name, (seconds, peak) in figures.items():
            memory = f"{peak / 1024:.1f} MiB" if peak else ""
            print(f"  {name:<32} {seconds:7.2f} s  {memory}")
    dense, rnd = results["dense"], results["random-ids"]
    pc = dense["python-can LogReader"][0]
    goals = [
        ("dense decode --summary vs python-can", pc / dense["decode --summary (columnar)"][0], 8),
        ("dense decode --json vs python-can", pc / dense["decode --json (columnar)"][0], 4),
        (
            "random-ids decode --summary vs python-can",
            rnd["python-can LogReader"][0] / rnd["decode --summary (columnar)"][0],
            3,
        ),
    ]
    if "log2asc" in dense:
        goals.append(
            (
                "dense decode --summary vs log2asc",
                dense["log2asc"][0] / dense["decode --summary (columnar)"][0],
                2,
            )
        )
    if "table" in results:
        table = results["table"]
        goals.append(
            ("table vs today", table["table (today)"][0] / table["table (columnar)"][0], 2)
        )
    print("\ngoal                                        ratio   goal")
    for name, ratio, goal in goals:
        verdict = "met" if ratio >= goal else "NOT met"
        print(f"  {name:<42} {ratio:5.2f}x  {goal}x  {verdict}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
