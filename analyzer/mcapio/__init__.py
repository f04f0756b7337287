"""MCAP recordings: channels and Foxglove views here, the sink in write/, the reader in read/."""

from __future__ import annotations
