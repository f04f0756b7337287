"""Safe output files: no silent overwrite, never over an input, never through a symlink."""

from __future__ import annotations

import contextlib
import errno
import io
import os
import stat
import tempfile
from collections.abc import Callable, Iterable
from io import FileIO
from pathlib import Path
from types import TracebackType
from typing import IO

from analyzer.errors import SourceError, UsageError
from analyzer.portable import NO_HARD_LINKS, open_fd, set_permissions

# The permissions of a new output file before the umask (what open() would give).
_FILE_MODE = 0o666


class OutputRefused(UsageError):
    """The output may not be written: it exists without --force, is an input, is a symlink."""


class OutputWriteError(SourceError):
    """The output could not be created or written (full disk, no permission...)."""


def describe_os_error(exc: OSError) -> str:
    """'No space left on device' rather than '[Errno 28] ...'; 'disk full' is said by callers."""
    return exc.strerror or str(exc)


def is_disk_full(exc: BaseException) -> bool:
    """True for the errors a full disk or an exhausted quota / file size limit gives."""
    return isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _same_file(a: os.stat_result, b: os.stat_result) -> bool:
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def check_output(
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    inputs: Iterable[str | os.PathLike[str]] = (),
    replaceable: Callable[[Path], bool] | None = None,
) -> Path:
    """Refuse an output path before any work starts; returns it as a Path.

    Refused (``OutputRefused``, exit code 2): a directory, a missing directory, a symlink
    (even a dangling one, even with ``force``), one of ``inputs`` (even with ``force``), an
    existing file unless ``force`` or ``replaceable(path)`` says this command may replace it.
    """
    target = Path(path)
    name = str(path)
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise OutputRefused(f"cannot write {name}: directory {parent} does not exist")
    try:
        info = os.lstat(target)
    except FileNotFoundError:
        return target
    except OSError as exc:
        raise OutputRefused(f"cannot write {name}: {describe_os_error(exc)}") from None
    if stat.S_ISLNK(info.st_mode):
        raise OutputRefused(
            f"{name} is a symbolic link; refusing to write through it (remove it or "
            "choose another name)"
        )
    if stat.S_ISDIR(info.st_mode):
        raise OutputRefused(f"{name} is a directory")
    for given in inputs:
        with contextlib.suppress(OSError):
            if _same_file(os.stat(given), info):
                raise OutputRefused(
                    f"writing {name} would overwrite the input {os.fspath(given)}; refused, "
                    "even with --force"
                )
    if not stat.S_ISREG(info.st_mode):
        raise OutputRefused(f"{name} exists and is not a regular file")
    if force or (replaceable is not None and replaceable(target)):
        return target
    raise OutputRefused(f"{name} exists; choose another name or use --force to overwrite it")


class OutputFile:
    """A file being written; the only way commands create their output files.

    ``atomic`` (the default): the data goes to an unpredictable temporary name created
    exclusively in the same directory (so nothing planted there is followed) and
    ``commit()`` renames it to the output name; ``discard()`` (or an exception inside a
    ``with`` block) removes it. Until then an existing output is untouched.

    ``atomic=False`` (live recordings that must be readable at their name if the recorder
    is killed): the output name itself is created exclusively (O_EXCL | O_NOFOLLOW); an
    existing file that may be replaced is removed first. ``discard()`` removes the file
    only if it is still the one created here.

    ``file`` is a binary, unbuffered file object (``buffered=True``: buffered), or a text
    stream when ``encoding`` is given. The checks of ``check_output`` run first.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        force: bool = False,
        inputs: Iterable[str | os.PathLike[str]] = (),
        replaceable: Callable[[Path], bool] | None = None,
        atomic: bool = True,
        buffered: bool = True,
        encoding: str | None = None,
    ) -> None:
        # Only what is there before the checks may be replaced; anything that appears later
        # makes the exclusive create (or the commit) fail.
        self._may_replace = os.path.lexists(path)
        self.path = check_output(path, force=force, inputs=inputs, replaceable=replaceable)
        self.name = os.fspath(path)
        self.atomic = atomic
        self._committed = False
        self._discarded = False
        directory = str(self.path.parent) if str(self.path.parent) else "."
        try:
            if atomic:
                fd, temp = tempfile.mkstemp(
                    prefix=f".{self.path.name}.", suffix=".partial", dir=directory
                )
                self.temp_path: str | None = temp
                set_permissions(fd, temp, _FILE_MODE & ~_umask())
            else:
                self.temp_path = None
                if self._may_replace:
                    os.unlink(self.path)  # never follows a link; O_EXCL below refuses one
                flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
                fd = open_fd(self.path, flags, _FILE_MODE)
        except FileExistsError:
            raise OutputRefused(
                f"{self.name} appeared while it was being created; not overwriting it"
            ) from None
        except OSError as exc:
            raise OutputWriteError(f"cannot create {self.name}: {describe_os_error(exc)}") from None
        try:
            self._stat = os.fstat(fd)
            raw = FileIO(fd, "wb", closefd=True)
        except BaseException:  # Ctrl-C / SIGTERM right after creating it: remove it again
            os.close(fd)
            with contextlib.suppress(OSError):
                os.unlink(self.temp_path or self.path)
            raise
        self.binary: IO[bytes] = io.BufferedWriter(raw) if buffered or encoding else raw
        self.file: IO[bytes] | IO[str] = (
            io.TextIOWrapper(self.binary, encoding=encoding, newline="")
            if encoding
            else self.binary
        )

    # -- lifetime --------------------------------------------------------------------------------

    @property
    def written_path(self) -> str:
        """Where the bytes are now (the temporary name until an atomic output is committed)."""
        if self.temp_path is not None and not self._committed:
            return self.temp_path
        return str(self.path)

    def commit(self) -> None:
        """Flush to disk and give the output its name. Raises OutputWriteError on failure
        (the temporary file is removed, an existing output is left as it was)."""
        if self._committed:
            return
        try:
            self.file.flush()
            os.fsync(self.binary.fileno())
            self.file.close()
            if self.temp_path is not None:
                self._rename_into_place(self.temp_path)
            self._committed = True
            _sync_directory(self.path.parent)
        except OSError as exc:
            self.discard()
            raise OutputWriteError(f"cannot write {self.name}: {describe_os_error(exc)}") from None

    def _rename_into_place(self, temp: str) -> None:
        try:
            info = os.lstat(self.path)
        except FileNotFoundError:
            info = None
        if info is not None and (stat.S_ISLNK(info.st_mode) or not self._may_replace):
            # something was planted at the name while we wrote: keep it and our data
            raise OutputRefused(
                f"{self.name} appeared while it was being written; the output is kept as {temp}"
            )
        if info is None:
            try:
                os.link(temp, self.path)  # fails if the name exists: never replaces
            except OSError as exc:
                if exc.errno == errno.EEXIST:
                    raise OutputRefused(
                        f"{self.name} appeared while it was being written; the output is kept "
                        f"as {temp}"
                    ) from None
                if exc.errno not in NO_HARD_LINKS:
                    raise
                os.replace(temp, self.path)
            else:
                os.unlink(temp)
            return
        os.replace(temp, self.path)

    def discard(self) -> None:
        """Close and remove what was written (only our own file). Safe to call twice."""
        if self._discarded or self._committed:
            return
        self._discarded = True
        with contextlib.suppress(OSError, ValueError):
            self.file.close()
        doomed = self.temp_path if self.temp_path is not None else str(self.path)
        with contextlib.suppress(OSError):
            if _same_file(os.lstat(doomed), self._stat):
                os.unlink(doomed)

    def close_keep(self) -> None:
        """Close without renaming or removing (a non-atomic output stays where it is)."""
        with contextlib.suppress(OSError, ValueError):
            self.file.close()
        if self.temp_path is None:
            self._committed = True

    def __enter__(self) -> OutputFile:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if kind is None:
            self.commit()
        else:
            self.discard()


def _sync_directory(directory: Path) -> None:
    """Make a rename durable (best effort: not every system can open a directory)."""
    with contextlib.suppress(OSError):
        fd = open_fd(str(directory) if str(directory) else ".", os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def write_output(
    path: str | os.PathLike[str],
    data: bytes | str,
    *,
    force: bool = False,
    inputs: Iterable[str | os.PathLike[str]] = (),
) -> Path:
    """Write a small output file in one go through an atomic ``OutputFile``."""
    encoding = "utf-8" if isinstance(data, str) else None
    with OutputFile(path, force=force, inputs=inputs, encoding=encoding) as out:
        out.file.write(data)  # type: ignore[arg-type]
    return out.path
