"""The optional extras (video, fleet, ardupilot): whether one is installed, and what to install."""

from __future__ import annotations

import importlib
from dataclasses import dataclass

from analyzer.errors import UsageError


@dataclass(frozen=True, slots=True)
class Extra:
    """An optional part of the installation: its name in pyproject.toml, the modules it
    brings (imported to tell whether it is there) and the packages they come from."""

    name: str
    modules: tuple[str, ...]
    packages: str

    @property
    def install(self) -> str:
        """How to get it, in a few words."""
        return f"install gimbal-analyzer[{self.name}] ({self.packages}; the manual's Install page)"

    @property
    def missing(self) -> str:
        """What a note says after what was left out."""
        return f"the {self.name} extra is not installed; {self.install}"


VIDEO = Extra("video", ("av", "cv2"), "PyAV, OpenCV")
FLEET = Extra("fleet", ("pyarrow", "duckdb"), "pyarrow, DuckDB")
ARDUPILOT = Extra("ardupilot", ("lupa",), "lupa")
EXTRAS = (VIDEO, FLEET, ARDUPILOT)


class MissingExtra(UsageError):
    """A command asked for something an extra that is not installed does: exit code 2."""


def installed(extra: Extra, uses: tuple[str, ...] | None = None) -> bool:
    """True when every module of ``extra`` (or those of it named in ``uses``) imports (a
    broken install counts as missing)."""
    for name in extra.modules if uses is None else uses:
        try:
            importlib.import_module(name)
        except ImportError:
            return False
    return True


def require(extra: Extra, what: str, uses: tuple[str, ...] | None = None) -> None:
    """Raise MissingExtra, in one line, when ``what`` (``record --video``) cannot run here.

    ``uses``: the modules of ``extra`` that ``what`` imports, when not all of them (an
    import only to check costs memory: DuckDB's is 20 MB, which ``table`` never uses)."""
    if not installed(extra, uses):
        raise MissingExtra(f"{what} needs the {extra.name} extra: {extra.install}")


def not_installed_note(extra: Extra, what: str) -> str | None:
    """The one line that says ``what`` was left out (None when the extra is installed)."""
    if installed(extra):
        return None
    return f"{what}: {extra.missing}"
