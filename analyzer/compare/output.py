"""How a comparison is shown: a table of the pairs with their figures and why, or JSON lines."""

from __future__ import annotations

import json
import math
from typing import IO

from analyzer.compare.figures import Rule
from analyzer.compare.judged import Judged
from analyzer.compare.pairs import Pair, summary
from analyzer.terminal_text import printable

WIDTH = {"kind": 16, "command": 16, "time": 8, "verdict": 11}


def window_words(one: Judged, other: Judged) -> str:
    """What of ``one`` is compared, in words."""
    start, _, _, _ = one.window(other)
    if one.marks is not None:
        m = one.marks
        ended = "" if m.ended is not None else " (it has no end mark: cut short)"
        return f"its replay of {m.flight}, {m.words()}{ended}"
    if other.marks is not None and math.isfinite(start):
        m = other.marks
        return f"{m.span_start_s:.1f} s to {m.span_end_s:.1f} s of it, the span the other replayed"
    if one.steps and other.steps:
        return "a check recording: its steps"
    return "all of it"


def sides(a: Judged, b: Judged) -> list[tuple[str, str]]:
    """("A", what A is and what of it is compared), and the same of B."""
    return [
        ("A", f"{a.name} ({a.described}): {window_words(a, b)}"),
        ("B", f"{b.name} ({b.described}): {window_words(b, a)}"),
    ]


def axis_words(a: Judged, b: Judged) -> str:
    """What the times of the pairs count from."""
    if a.marks is not None or b.marks is not None:
        return "times: seconds from the start of the replayed span, in the flight's time"
    return "times: seconds from each recording's first message"


def header(a: Judged, b: Judged) -> list[str]:
    return [f"{side}  {text}" for side, text in sides(a, b)] + [axis_words(a, b)]


def figures_text(pair: Pair, rules: tuple[Rule, ...]) -> str:
    """'pan ratio 1.00 | 0.51, lag 0.30 | 0.30 s': A | B."""
    parts = []
    for rule, a, b in pair.figures(rules):
        unit = f" {rule.unit}" if rule.unit else ""
        parts.append(f"{rule.label} {rule.show(a)} | {rule.show(b)}{unit}")
    return ", ".join(parts)


def table(pairs: list[Pair], rules: tuple[Rule, ...], a: Judged, b: Judged, out: IO[str]) -> None:
    """The pairs as a table under a header, then a one-line summary."""
    w = WIDTH
    for line in header(a, b):
        out.write(printable(line) + "\n")
    out.write("\n")
    if not pairs:
        out.write("nothing to compare: no judged command in either\n")
        return
    out.write(
        f"{'kind':<{w['kind']}} {'command':<{w['command']}} {'A s':>{w['time']}} "
        f"{'B s':>{w['time']}}  {'verdict A':<{w['verdict']}} verdict B\n"
    )
    for pair in pairs:
        first = pair.first
        at_a = f"{pair.a.at:.2f}" if pair.a else "-"
        at_b = f"{pair.b.at:.2f}" if pair.b else "-"
        verdict_a = pair.a.verdict if pair.a else "-"
        verdict_b = pair.b.verdict if pair.b else "-"
        out.write(
            f"{first.kind:<{w['kind']}} {printable(first.command):<{w['command']}} "
            f"{at_a:>{w['time']}} {at_b:>{w['time']}}  {verdict_a:<{w['verdict']}} "
            f"{verdict_b:<{w['verdict']}} {'DIFFERS' if pair.differs else 'same'}\n"
        )
        shown = figures_text(pair, rules)
        if shown:
            out.write(f"{'':<{w['kind']}} {shown}\n")
        for why in pair.why:
            out.write(f"{'':<{w['kind']}} why: {printable(why)}\n")
    out.write("\n" + verdict_line(pairs) + "\n")


def verdict_line(pairs: list[Pair]) -> str:
    differ = [p for p in pairs if p.differs]
    if not differ:
        return f"{len(pairs)} pairs, none differs: the gimbal behaved the same in A and B"
    which = ", ".join(f"{p.first.kind} at {p.at:.2f} s" for p in differ[:5])
    more = f" and {len(differ) - 5} more" if len(differ) > 5 else ""
    return (
        f"{len(pairs)} pairs, {len(differ)} differ: the gimbal behaved differently ({which}{more})"
    )


def json_lines(
    pairs: list[Pair], rules: tuple[Rule, ...], a: Judged, b: Judged, out: IO[str]
) -> None:
    """One object per pair, then the summary."""
    for pair in pairs:
        out.write(json.dumps(pair.to_json(rules)) + "\n")
    out.write(json.dumps(summary(pairs, a.name, b.name)) + "\n")
