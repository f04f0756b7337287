"""The verdicts of a run counted as analyze says them: commands apart from feedback health."""

from __future__ import annotations

from collections import Counter
from typing import Any

from analyzer.analysis.findings import FEEDBACK_COMMAND, verdict_line
from analyzer.protocol.response_fields import CHECK_FEEDBACK_GAP, HEALTH_VERDICTS, HEALTH_WORDS
from analyzer.summary import gap_words


class VerdictCounts:
    """Findings counted as ``analyze`` counts them: the commands' verdicts, the feedback's
    minutes by health, and its gaps with the messages they lost."""

    def __init__(self) -> None:
        self.verdicts: Counter[str] = Counter()  # of the commands' findings
        self.health: Counter[str] = Counter()  # of the feedback windows, by verdict
        self.gaps = self.lost = 0

    def add(self, fields: dict[str, Any]) -> None:
        verdict = str(fields.get("verdict"))
        if fields.get("command") != FEEDBACK_COMMAND:
            self.verdicts[verdict] += 1
        elif fields.get("check") == CHECK_FEEDBACK_GAP:
            self.gaps += 1
            self.lost += int(fields.get("lost_messages", 1))
        else:
            self.health[verdict] += 1

    def clear(self) -> None:
        self.verdicts.clear()
        self.health.clear()
        self.gaps = self.lost = 0

    def verdict_line(self) -> str:
        """'4 obeyed, 1 partial, 3 not obeyed, 2 unknown' (the commands' findings)."""
        return verdict_line(self.verdicts)

    def health_line(self) -> str:
        """'2 minutes healthy, 1 degraded; 1 gap, 1 message lost (...)'."""
        windows = [
            f"{n} {HEALTH_WORDS[v].lower()}"
            for v in HEALTH_VERDICTS
            if (n := self.health.get(v, 0))
        ]
        if windows:
            total = sum(self.health.values())
            minutes = f" of {total} minute{'s' if total > 1 else ''} "
            windows[0] = windows[0].replace(" ", minutes, 1)
        return "; ".join([", ".join(windows) or "not judged", gap_words(self.gaps, self.lost)])
