"""Sub-commands of the gimbal-analyzer command line, one module each."""

from __future__ import annotations
