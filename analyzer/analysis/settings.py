"""The response analysis' knobs (the ``analyze`` options) and their defaults."""

from __future__ import annotations

from dataclasses import dataclass

from analyzer.feedback_track import EXPECTED_FEEDBACK_HZ

DEFAULT_TOLERANCE_DEG = 1.0
DEFAULT_TIME_ALLOWED_S = 5.0
# A state flag (tracking) shows a change in the next feedback messages: three periods.
FLAG_PERIODS = 3
DEFAULT_FLAG_ALLOWED_S = FLAG_PERIODS / EXPECTED_FEEDBACK_HZ  # 1.5 s at the document's 2 Hz


@dataclass(frozen=True)
class Settings:
    """The judgement's knobs (the ``analyze`` options)."""

    tolerance_deg: float = DEFAULT_TOLERANCE_DEG
    time_allowed_s: float = DEFAULT_TIME_ALLOWED_S  # for a target (an angle) to be reached
    flag_allowed_s: float = DEFAULT_FLAG_ALLOWED_S  # for a state flag (tracking) to change

    def __post_init__(self) -> None:
        if not self.tolerance_deg > 0:
            raise ValueError("the tolerance must be more than 0 deg")
        if not self.time_allowed_s > 0:
            raise ValueError("the time allowed must be more than 0 s")
        if not self.flag_allowed_s > 0:
            raise ValueError("the time allowed for a state flag must be more than 0 s")
