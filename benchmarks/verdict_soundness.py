"""How sound are the verdicts? Seeded random scenarios (``tests/soundness.py``): healthy
simulated gimbals must get no false alarm, every fault model must be named.

    python benchmarks/verdict_soundness.py                  200 seeds, 20 with the camera
    python benchmarks/verdict_soundness.py --seeds 50 --camera 4 --first-seed 1000

For each seed: a healthy gimbal and one of each fault model (frozen, sluggish, late,
the wrong way, drift, ignoring a command, geodetic yaw taken from the nose), started
anywhere in their range, driven by a random ground-station script and judged by
``analyze`` and by the monitor's "Did it obey?" panel, and driven by ``check`` (a
random subset of its steps, from the simulated bench in virtual time) with the
findings of its recording; the camera's seeds record the simulated camera's video
(healthy, and a lens that ignores zoom) and judge it with ``analyze``. The demo's
link faults in three scenarios of four, a feedback outage in one of four, runs cut at
random moments. Prints a Markdown table: scenarios, false alarms (a healthy gimbal's
scenarios with a partial / not_obeyed finding or a failed step) and misses (a fault's
scenarios in which nothing named it), then the false alarms and misses themselves.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.soundness import HEALTHY, Outcome, run, scenarios

# The views of a scenario: (where it was run, the view of its verdicts) -> the row's name
VIEWS = {
    ("analyze", "analyze"): "analyze",
    ("analyze", "monitor"): "monitor panel",
    ("check", "check"): "check steps",
    ("check", "recording"): "check's recording",
    ("camera", "camera"): "analyze (camera)",
}


def table(outcomes: list[Outcome]) -> list[str]:
    """The Markdown table: one row per view for healthy gimbals, one per model and
    where it was judged for the faults."""
    rows: dict[tuple[str, str], list[int]] = defaultdict(lambda: [0, 0, 0])
    for o in outcomes:
        s = o.scenario
        if s.model == HEALTHY:
            for view, alarms in o.alarms.items():
                counts = rows[(VIEWS[(s.where, view)], HEALTHY)]
                counts[0] += 1
                counts[1] += bool(alarms)
        else:
            where = "analyze + monitor" if s.where == "analyze" else VIEWS[(s.where, s.where)]
            counts = rows[(where, s.model)]
            counts[0] += 1
            counts[2] += not o.named
    lines = [
        "| judged by | gimbal | scenarios | false alarms | misses | named |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for (view, model), (n, false_alarms, misses) in rows.items():
        if model == HEALTHY:
            lines.append(f"| {view} | healthy | {n} | {false_alarms} | - | - |")
        else:
            named = 100.0 * (n - misses) / n
            lines.append(
                f"| {view} | {model.replace('_', ' ')} | {n} | - | {misses} | {named:.1f} % |"
            )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=200, help="seeds of each (default 200)")
    parser.add_argument("--camera", type=int, default=20, help="seeds with video (default 20)")
    parser.add_argument("--first-seed", type=int, default=0, help="the first seed (default 0)")
    args = parser.parse_args()
    todo = list(scenarios(args.seeds, first_seed=args.first_seed, camera=args.camera))
    outcomes: list[Outcome] = []
    began = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        for n, scenario in enumerate(todo, 1):
            outcomes.append(run(scenario, Path(folder)))
            if n % 100 == 0 or n == len(todo):
                took = time.perf_counter() - began
                print(f"  {n}/{len(todo)} scenarios, {took:.0f} s", file=sys.stderr, flush=True)
    seeds = f"seeds {args.first_seed}..{args.first_seed + args.seeds - 1}"
    print(
        f"{len(outcomes)} scenarios ({seeds}, {args.camera} with the camera's video) "
        f"in {time.perf_counter() - began:.0f} s"
    )
    print()
    print("\n".join(table(outcomes)))
    problems = [o for o in outcomes if any(o.alarms.values()) or o.named is False]
    if problems:
        print()
        for o in problems:
            what = "MISS" if o.named is False else "FALSE ALARM"
            print(f"{what} {o.scenario} ({o.about})")
            said = [f"{view}: {line}" for view, lines in o.alarms.items() for line in lines]
            for line in (said or o.said)[:4]:
                print(f"    {line[:300]}")


if __name__ == "__main__":
    main()
