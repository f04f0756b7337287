"""Every test collected, kept before ``-m`` / ``-k`` leave some out (conftest.py fills it)."""

from __future__ import annotations

import pytest

ALL_ITEMS = pytest.StashKey[list[pytest.Item]]()
