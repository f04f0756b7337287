"""Errors that reach the user as one clear line instead of a traceback."""

from __future__ import annotations


class UsageError(Exception):
    """Bad input from the user (unknown file format, bad option value...): exit code 2."""


class SourceError(Exception):
    """A capture source could not be opened or failed for good: exit code 1."""
