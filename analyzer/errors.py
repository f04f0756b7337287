"""Errors that reach the user as one clear line, and the exit codes every command uses."""

from __future__ import annotations

import textwrap

# The exit codes of every command (--help and the manual's "Exit codes" page show this table).
EXIT_OK = 0
EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130

EXIT_CODES: tuple[tuple[int, str], ...] = (
    (
        EXIT_OK,
        "success; also a record / monitor / demo ended by Ctrl-C or SIGTERM, "
        "and output cut short by its reader (| head)",
    ),
    (
        EXIT_FAILED,
        "the work started but failed: a write failure (disk full, standard output "
        "unwritable), a source that failed, a live capture that never received anything, "
        "a step of a bench check that failed, a replay stopped by a silent gimbal; "
        "compare: the two recordings differ",
    ),
    (
        EXIT_USAGE,
        "bad usage, an input that cannot be read or recognised, an output refused "
        "(exists without --force, is one of the inputs, is a symlink)",
    ),
    (EXIT_INTERRUPTED, "interrupted (Ctrl-C or SIGTERM) before anything useful was done"),
)


def exit_code_table(width: int = 80) -> str:
    """The table as plain text, for ``--help``: each code's words wrapped to ``width``
    under one another."""
    return "\n".join(
        textwrap.fill(words, width, initial_indent=f"  {code:<4} ", subsequent_indent=" " * 7)
        for code, words in EXIT_CODES
    )


class UsageError(Exception):
    """Bad input from the user (unknown file format, bad option value...): exit code 2."""


class InputError(UsageError):
    """An input file that cannot be read or is not what it claims to be: exit code 2."""


class NothingReadable(InputError):
    """An input that holds nothing this tool can read: the message says so in one line and
    ``details`` lists what the input holds instead (exit code 2)."""

    def __init__(self, message: str, details: tuple[str, ...] = ()) -> None:
        super().__init__(message)
        self.details = details


class SourceError(Exception):
    """A capture source could not be opened or failed for good: exit code 1."""


class OutputError(Exception):
    """Writing an output failed (disk full, standard output unwritable): exit code 1."""


class OutputClosed(BrokenPipeError):
    """The reader of standard output went away (``| head``): end quietly, exit code 0."""


class Terminated(KeyboardInterrupt):
    """SIGTERM (Windows: Ctrl-Break, the console closed), handled like Ctrl-C:
    ``signal_name`` says which one it was."""

    signal_name: str = "SIGTERM"
