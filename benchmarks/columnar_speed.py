"""The columnar path against python-can, can-utils' log2asc and the path before it, in one run.

    python benchmarks/columnar_speed.py [--frames N] [--repeat N] [--log2asc PATH]
                                        [--before REV] [--keep DIR] [--no-table]

Writes the dense and random-ids candump logs of ``decode_speed.py`` (values change in
every frame: a moving gimbal, a pilot's stick, moving GPS; 36 % gimbal and UAV frames,
80 foreign IDs or a new foreign ID in every foreign frame), the dense log's frames as
Vector BLF (written by python-can's ``BLFWriter``) and a dense log of twice the frames
for ``table``. Then it measures, as CPU seconds of a fresh process (start-up included,
bytecode compiled as an install has it), the best of ``--repeat`` runs each, and the
process's peak memory:

- python-can iterating each file (``can.LogReader``, ``can.BLFReader``), no decoding;
- can-utils' ``log2asc`` converting the dense log to ASC (C; found on PATH or given with
  ``--log2asc``; built from can-utils' source, it is not part of this project);
- ``decode --summary``, ``decode --json`` and ``table`` by this tree (the columnar path)
  and by the tree of ``--before`` (default: the last commit before the columnar path,
  "today's path"), which is taken out of git into a temporary folder.

Prints every figure side by side, the load of the machine before and after, and the
goals of the columnar path with their ratios.
"""

from __future__ import annotations

import argparse
import compileall
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.decode_speed import write_log  # noqa: E402

BEFORE = "41babadff26d1182dd7450561658b5c086061a4e"  # the last commit before the columnar path

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
reader = can.BLFReader(sys.argv[1]) if sys.argv[1].endswith(".blf") else can.LogReader(sys.argv[1])
n = 0
for _ in reader:
    n += 1
print(n)
"""
BLF_WRITER = """
import sys, can
with can.BLFWriter(sys.argv[2]) as writer:
    for message in can.LogReader(sys.argv[1]):
        writer.on_message_received(message)
"""

Figure = tuple[float, int]  # CPU seconds, peak memory in KiB (0: not measured)


def cpu(command: list[str], env: dict[str, str] | None, cwd: Path) -> Figure:
    """CPU seconds of a child process (its output thrown away) and its peak memory."""
    before = os.times()
    proc = subprocess.run(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, cwd=cwd, check=False
    )
    after = os.times()
    if proc.returncode != 0:
        raise SystemExit(f"{command[:4]} failed: {proc.stderr.decode(errors='replace')[-400:]}")
    seconds = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    words = proc.stderr.decode(errors="replace").split()
    peak = int(words[-2]) if len(words) >= 2 and words[-1] == "kB" else 0
    return seconds, peak


class Bench:
    """Runs every command of the comparison, each ``repeat`` times, the fastest counts."""

    def __init__(self, repeat: int, before: Path, scratch: Path) -> None:
        self.repeat = repeat
        self.trees = {"columnar": ROOT, "today": before}
        self.scratch = scratch

    def best(self, command: list[str], env: dict[str, str] | None = None) -> Figure:
        runs = [cpu(command, env, self.scratch) for _ in range(self.repeat)]
        return min(r[0] for r in runs), max(r[1] for r in runs)

    def ours(self, tree: str, *argv: str) -> Figure:
        env = {**os.environ, "PYTHONPATH": str(self.trees[tree])}
        env.pop("OPENBLAS_NUM_THREADS", None)  # what each tree's command line does of it
        return self.best([sys.executable, "-c", CHILD, *argv], env)

    def table(self, tree: str, path: Path) -> Figure:
        """``table`` of ``path`` into a fresh dataset each time (else it skips the file)."""
        runs = []
        for n in range(self.repeat):
            dataset = self.scratch / f"fleet-{tree}-{n}"
            shutil.rmtree(dataset, ignore_errors=True)
            env = {**os.environ, "PYTHONPATH": str(self.trees[tree])}
            argv = ["table", str(path), "-o", str(dataset), "--workers", "1", "-q"]
            runs.append(cpu([sys.executable, "-c", CHILD, *argv], env, self.scratch))
            shutil.rmtree(dataset, ignore_errors=True)
        return min(r[0] for r in runs), max(r[1] for r in runs)


def tree_before(rev: str, folder: Path) -> Path:
    """The analyzer package of ``rev``, out of git, compiled."""
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", rev, "analyzer"], capture_output=True, check=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    compileall.compile_dir(str(folder / "analyzer"), quiet=1)
    return folder


def measure(args: argparse.Namespace, folder: Path, bench: Bench) -> dict[str, dict[str, Figure]]:
    files = {mix: folder / f"columnar-{mix}.log" for mix in ("dense", "random-ids")}
    for mix, path in files.items():
        if not path.exists():
            print(f"writing {args.frames:,} frames of the {mix} mix ...", flush=True)
            write_log(path, args.frames, mix)
    blf = folder / "columnar-dense.blf"
    if not blf.exists():
        print("writing the dense frames as BLF with python-can ...", flush=True)
        writer = [sys.executable, "-c", BLF_WRITER, str(files["dense"]), str(blf)]
        subprocess.run(writer, check=True)
    double = folder / "columnar-dense-2x.log"
    if args.table and not double.exists():
        print(f"writing {2 * args.frames:,} frames of the dense mix for table ...", flush=True)
        write_log(double, 2 * args.frames, "dense")
    print("measuring ...", flush=True)
    results: dict[str, dict[str, Figure]] = {}
    for name, path in (*files.items(), ("BLF", blf)):
        row = results[name] = {}
        row["python-can"] = bench.best([sys.executable, "-c", PYTHON_CAN, str(path)])
        if name == "dense" and args.log2asc:
            row["log2asc"] = bench.best([args.log2asc, "-I", str(path), "-O", os.devnull, "can0"])
        for tree in ("today", "columnar"):
            row[f"decode --summary ({tree})"] = bench.ours(tree, "decode", "--summary", str(path))
            if name != "BLF":
                row[f"decode --json ({tree})"] = bench.ours(tree, "decode", "--json", str(path))
    if args.table:
        row = results["table, 2x frames"] = {}
        for tree in ("today", "columnar"):
            row[f"table ({tree})"] = bench.table(tree, double)
    return results


def goals(results: dict[str, dict[str, Figure]]) -> list[tuple[str, float, float]]:
    dense, random_ids, blf = results["dense"], results["random-ids"], results["BLF"]
    summary = "decode --summary (columnar)"
    out = [
        ("dense decode --summary vs python-can", dense["python-can"][0] / dense[summary][0], 8),
        (
            "dense decode --json vs python-can",
            dense["python-can"][0] / dense["decode --json (columnar)"][0],
            4,
        ),
        ("BLF decode --summary vs python-can", blf["python-can"][0] / blf[summary][0], 4),
        (
            "random-ids decode --summary vs python-can",
            random_ids["python-can"][0] / random_ids[summary][0],
            3,
        ),
    ]
    if "log2asc" in dense:
        against = dense["log2asc"][0] / dense[summary][0]
        out.insert(1, ("dense decode --summary vs log2asc", against, 2))
    if "table, 2x frames" in results:
        table = results["table, 2x frames"]
        out.append(("table vs today", table["table (today)"][0] / table["table (columnar)"][0], 2))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--frames", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3, help="runs of each; the fastest counts")
    parser.add_argument("--log2asc", help="can-utils' log2asc (default: the one on PATH)")
    parser.add_argument("--before", default=BEFORE, help="the tree of today's path (a git rev)")
    parser.add_argument("--no-table", dest="table", action="store_false", help="leave table out")
    parser.add_argument("--keep", metavar="DIR", help="write the logs here and keep them")
    args = parser.parse_args()
    args.log2asc = args.log2asc or shutil.which("log2asc")
    if not args.log2asc:
        print("log2asc not found (not on PATH, no --log2asc): its column is left out")
    compileall.compile_dir(str(ROOT / "analyzer"), quiet=1)
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(args.keep or scratch)
        folder.mkdir(parents=True, exist_ok=True)
        # Each tree in a folder of its own; the commands run in another (a child's working
        # folder comes first on its path).
        (Path(scratch) / "today").mkdir()
        (Path(scratch) / "runs").mkdir()
        before = tree_before(args.before, Path(scratch) / "today")
        bench = Bench(args.repeat, before, Path(scratch) / "runs")
        load = os.getloadavg()
        results = measure(args, folder, bench)
        after = os.getloadavg()
    print()
    print(f"load before: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} (1, 5, 15 minutes)")
    print(f"load after:  {after[0]:.2f} {after[1]:.2f} {after[2]:.2f}")
    for name, figures in results.items():
        print(f"\n[{name}]  CPU s (best of {args.repeat}), peak memory")
        for what, (seconds, peak) in figures.items():
            memory = f"{peak / 1024:.1f} MiB" if peak else ""
            print(f"  {what:<34} {seconds:7.2f} s  {memory}")
    print("\ngoal                                          ratio   goal")
    for name, ratio, goal in goals(results):
        verdict = "met" if ratio >= goal else "NOT met"
        print(f"  {name:<44} {ratio:5.2f}x  {goal}x  {verdict}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
