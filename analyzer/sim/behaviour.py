"""How the simulated gimbal disobeys: sluggish, short, ignoring, drifting, late, the wrong way,
the wrong yaw frame."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Behaviour:
    """How far the simulated gimbal does what it is told (the defaults: exactly)."""

    speed: float = 1.0  # fraction of commanded rates and of the slew speed (sluggish < 1)
    reach: float = 1.0  # fraction of the way to a target it goes before stopping (short < 1)
    ignore: frozenset[str] = frozenset()  # command names it does not act on
    drift_s: float = 0.0  # keeps turning this much longer after gimbal_control stops
    geodetic_as_airframe: bool = False  # takes geodetic yaw targets from the airframe's nose
    lag_s: float = 0.0  # acts on each command this much later than it came
    wrong_way: bool = False  # turns the other way for gimbal_control speeds

    def __post_init__(self) -> None:
        if not 0.0 <= self.speed <= 10.0:
            raise ValueError(f"speed factor {self.speed}: must be between 0 and 10")
        if not 0.0 <= self.reach <= 1.0:
            raise ValueError(f"reach {self.reach}: must be between 0 and 1")
        if self.drift_s < 0:
            raise ValueError(f"drift {self.drift_s} s: must not be negative")
        if not 0.0 <= self.lag_s <= 10.0:
            raise ValueError(f"lag {self.lag_s} s: must be between 0 and 10")

    @property
    def active(self) -> bool:
        return self != Behaviour()

    def describe(self) -> str:
        parts = []
        if self.speed == 0.0:
            parts.append("does not move at all (frozen)")
        elif self.speed != 1.0:
            parts.append(f"moves at {self.speed * 100:g}% of the asked speed")
        if self.reach != 1.0:
            parts.append(f"stops {self.reach * 100:g}% of the way to a target")
        if self.ignore:
            parts.append("ignores " + ", ".join(sorted(self.ignore)))
        if self.drift_s:
            parts.append(f"keeps turning {self.drift_s:g} s after gimbal_control stops")
        if self.geodetic_as_airframe:
            parts.append("takes geodetic yaw targets from the airframe's nose")
        if self.lag_s:
            parts.append(f"acts on each command {self.lag_s:g} s late")
        if self.wrong_way:
            parts.append("turns the other way for gimbal_control speeds")
        return "; ".join(parts) or "obeys"
