"""Every Debian package CI installs for the tests is named in the manual's development page."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def installed_by_ci() -> set[str]:
    """The packages `.ci/run` hands to apt-get install (directly or through a variable)."""
    text = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    packages: set[str] = set()
    for names in re.findall(r'^\w+_packages="([^"]+)"', text, flags=re.M):
        packages.update(names.replace("\\", " ").split())
    for line in re.findall(r"apt-get [^\n]*install [^\n]*", text):
        words = [w for w in line.split() if re.fullmatch(r"[a-z0-9][a-z0-9.+-]+", w)]
        packages.update(w for w in words if w not in {"apt-get", "install", "update"})
    return packages


def test_the_development_page_lists_every_package_ci_installs() -> None:
    packages = installed_by_ci()
    assert {"tshark", "chromium", "gstreamer1.0-x", "gir1.2-gst-rtsp-server-1.0"} <= packages
    page = (ROOT / "docs" / "howto" / "development.md").read_text(encoding="utf-8")
    missing = sorted(p for p in packages if f"`{p}" not in page and f" {p}" not in page)
    assert not missing, f"docs/howto/development.md does not name {missing}"
