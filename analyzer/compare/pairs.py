"""Two recordings' judged items paired by kind and order, and whether the gimbal behaved apart."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from analyzer.compare.figures import Rule
from analyzer.compare.judged import Item


@dataclass(frozen=True)
class Pair:
    """The n-th item of one kind in A and in B (either may be missing), and why they
    differ (``why`` empty: the gimbal behaved the same)."""

    a: Item | None
    b: Item | None
    why: tuple[str, ...]

    @property
    def differs(self) -> bool:
        return bool(self.why)

    @property
    def first(self) -> Item:
        item = self.a or self.b
        assert item is not None
        return item

    @property
    def at(self) -> float:
        return self.first.at

    def figures(self, rules: tuple[Rule, ...]) -> list[tuple[Rule, Any, Any]]:
        """(rule, A's value, B's value) of every figure either side has."""
        a = self.a.figures if self.a is not None else {}
        b = self.b.figures if self.b is not None else {}
        return [
            (r, a.get(r.name), b.get(r.name))
            for r in rules
            if _number(a.get(r.name)) or _number(b.get(r.name))
        ]

    def to_json(self, rules: tuple[Rule, ...]) -> dict[str, Any]:
        """One line of ``compare --json``: command, times, verdicts, NAME_a / NAME_b of
        every figure, differs, why."""
        first = self.first
        out: dict[str, Any] = {
            "command": first.command,
            "kind": first.kind,
            "check": first.check,
            "time_a": self.a.time if self.a else None,
            "time_b": self.b.time if self.b else None,
            "at_a": round(self.a.at, 3) if self.a else None,
            "at_b": round(self.b.at, 3) if self.b else None,
            "verdict_a": self.a.verdict if self.a else None,
            "verdict_b": self.b.verdict if self.b else None,
        }
        for rule, a, b in self.figures(rules):
            out[f"{rule.name}_a"] = a if _number(a) else None
            out[f"{rule.name}_b"] = b if _number(b) else None
        out["differs"] = self.differs
        out["why"] = "; ".join(self.why)
        return out


def _number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def pair_items(a: list[Item], b: list[Item], rules: tuple[Rule, ...]) -> list[Pair]:
    """Pairs in time order: the n-th item of a kind (command and check) in A with the n-th
    of the same in B; one without a partner is a pair of its own, and differs."""
    keys = list(dict.fromkeys(item.key for item in [*a, *b]))
    pairs = []
    for key in keys:
        mine = [i for i in a if i.key == key]
        theirs = [i for i in b if i.key == key]
        for n in range(max(len(mine), len(theirs))):
            one = mine[n] if n < len(mine) else None
            other = theirs[n] if n < len(theirs) else None
            pairs.append(Pair(one, other, tuple(differences(one, other, rules))))
    return sorted(pairs, key=lambda p: p.at)


def differences(a: Item | None, b: Item | None, rules: tuple[Rule, ...]) -> list[str]:
    """Why the gimbal behaved differently: a pair with one side missing, another verdict,
    a figure apart by more than its band."""
    if a is None or b is None:
        present = a or b
        assert present is not None
        side, other = ("A", "B") if a is not None else ("B", "A")
        return [
            f"only in {side}: {other} has no {present.kind} ({present.command}) to pair it with"
        ]
    out = []
    if a.verdict != b.verdict:
        out.append(f"verdict {a.verdict} | {b.verdict}")
    for rule in rules:
        mine, theirs = a.figures.get(rule.name), b.figures.get(rule.name)
        if isinstance(mine, (int, float)) and isinstance(theirs, (int, float)):
            why = rule.apart(float(mine), float(theirs))
            if why:
                out.append(why)
    return out


def summary(pairs: list[Pair], a: str, b: str) -> dict[str, Any]:
    """The last line of ``compare --json``."""
    differ = [p for p in pairs if p.differs]
    return {
        "summary": {
            "a": a,
            "b": b,
            "pairs": len(pairs),
            "same": len(pairs) - len(differ),
            "differ": len(differ),
            "only_a": sum(1 for p in pairs if p.b is None),
            "only_b": sum(1 for p in pairs if p.a is None),
            "differs": bool(differ),
        }
    }
