"""ASC, TRC and CSV through python-can, line by line: a damaged line is reported, reading goes on.

python-can's readers are generators: the first exception a damaged line raises ends
them, and a generator cannot be resumed. So the lines are fed to the reader by
``LineFeed``, which counts them; when the reader raises, the line it was on is reported
with its number, and a fresh reader is started on the rest of the file with the file's
header lines replayed in front (uncounted), so it knows the number base, the columns
and the start time again. A damaged line python-can would skip without a word (an ASC
line whose time is damaged, a TRC line of an unknown type: ``skipped_lines``) is raised
as it is handed out, and reported the same way. Each damaged line costs one new reader;
python-can keeps doing all the parsing of the many layouts these formats have.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from typing import Any

from analyzer.inputs.base import ABSOLUTE, DELTA
from analyzer.inputs.python_can.skipped_lines import SkippedLine, asc_problem, trc_checker
from analyzer.inputs.textlines import MAX_LINE, damage_after_line, open_lines, split_blocks
from analyzer.protocol.types import BAD_LINE, Event, diagnostic

RAW_LIMIT = 200  # characters of a bad line kept in its diagnostic
_ASC_HEADER = re.compile(r"\s*(date\s|base\s|//|(no\s+)?internal\s+events\s+logged)", re.I)
_ASC_RELATIVE = re.compile(r"\s*base\s+\w+\s+timestamps\s+relative", re.I)
_ASC_TRIGGER = re.compile(r"\s*begin\s+triggerblock\b", re.I)
_ASC_END_OF_HEADER = "no internal events logged\n"  # ends python-can's header scan cleanly
# python-can's CSVReader skips the first line it is given as the header: a file without
# one gets this in front, so that no frame line is taken for a header.
_CSV_HEADER = "timestamp,arbitration_id,extended,remote,error,dlc,data\n"


class LineFeed:
    """The file's lines as python-can's readers iterate them, with replayed header lines.

    ``lineno`` is the number of the last real line handed out; replayed lines do not
    count. ``watch`` (optional) sees every real line; ``check`` (optional) says why a
    real line is damage python-can would skip without a word, and it is then raised as
    ``SkippedLine`` in place of the line.
    """

    def __init__(self, lines: Iterator[str], replay: list[str]) -> None:
        self._lines = lines
        self._replay = replay
        self.lineno = 0
        self.last = ""
        self.watch: Callable[[str], None] | None = None
        self.check: Callable[[str], str | None] | None = None

    def restart(self, replay: list[str]) -> None:
        self._replay = list(replay)

    def __iter__(self) -> LineFeed:
        return self

    def __next__(self) -> str:
        if self._replay:
            return self._replay.pop(0)
        line = next(self._lines)
        self.lineno += 1
        self.last = line
        if self.watch is not None:
            self.watch(line)
        if self.check is not None and (problem := self.check(line)) is not None:
            raise SkippedLine(problem)
        return line

    def readline(self) -> str:
        try:
            return next(self)
        except StopIteration:
            return ""

    def close(self) -> None:  # python-can closes its file when it is done
        pass


def text_lines(raw: Any, problems_out: list[str]) -> Iterator[str]:
    """The decoded lines of a plain or gzip-compressed text file (gzip damage reported)."""
    blocks, problems = open_lines(raw)
    for lines in split_blocks(blocks):
        for line in lines:
            if len(line) > MAX_LINE:
                line = line[:MAX_LINE]  # the parser will refuse it; the cut is said then
            yield line.decode("utf-8", "replace") + "\n"
        if problems:
            problems_out.extend(problems)
            problems.clear()
    problems_out.extend(problems)


class TextLogReading:
    """Reads one ASC / TRC / CSV file with restarts; yields frames' messages and diagnostics.

    ``make_reader(feed)`` builds a python-can reader on a LineFeed. ``header`` is how
    many leading lines to replay, decided by ``is_header`` per format.
    """

    def __init__(
        self,
        fmt: str,
        lines: Iterator[str],
        make_reader: Callable[[LineFeed], Any],
        source: str,
        damage: list[str],
    ) -> None:
        self.fmt = fmt
        self.source = source
        self.make_reader = make_reader
        self.damage = damage
        self.header: list[str] = []
        body = self._take_header(lines)
        # Header lines are replayed to every reader (the first one too), so the line
        # count starts after them.
        self.feed = LineFeed(_chain(body, lines), [])
        self.feed.lineno = len(self.header)
        self.bad_lines = 0
        self.trigger: str | None = None
        self.time_base = ABSOLUTE
        if fmt == "asc":
            if any(_ASC_RELATIVE.match(line) for line in self.header):
                self.time_base = DELTA
            self.feed.watch = self._watch_asc
            self.feed.check = asc_problem
        elif fmt == "trc":
            self.feed.check = trc_checker(self.header)
        self.last_time = 0.0

    def _take_header(self, lines: Iterator[str]) -> list[str]:
        """Read the leading header lines into ``header``; returns the first body line."""
        for line in lines:
            if not self._is_header(line, len(self.header) + 1):
                return [line]
            self.header.append(line)
        return []

    def _is_header(self, line: str, number: int) -> bool:
        if self.fmt == "csv":
            return number == 1 and line.lower().startswith("timestamp")
        if self.fmt == "trc":
            return line.lstrip().startswith(";")
        return bool(_ASC_HEADER.match(line)) or not line.strip()

    def _watch_asc(self, line: str) -> None:
        if _ASC_TRIGGER.match(line):
            self.trigger = line

    def _replay(self) -> list[str]:
        replay = list(self.header)
        if self.fmt == "csv" and not replay:
            replay.append(_CSV_HEADER)
        if self.fmt == "asc":
            replay.append(_ASC_END_OF_HEADER)
            if self.trigger is not None:
                replay.append(self.trigger)
        return replay

    def messages(self) -> Iterator[Any]:
        """python-can messages and diagnostic Events, in file order."""
        feed = self.feed
        if feed.check is not None:  # a frame's line taken for the header (made a comment)
            for number, line in enumerate(self.header, 1):
                if (problem := feed.check(line)) is not None:
                    yield self.bad_line(number, line, SkippedLine(problem))
        feed.restart(self._replay())
        reported = 0
        while True:
            started = feed.lineno
            reader = self.make_reader(feed)
            iterator = iter(reader)
            while True:
                try:
                    msg = next(iterator)
                except StopIteration:
                    yield from self._damage_since(reported)
                    return
                except Exception as exc:  # python-can's generator dies on a damaged line
                    yield from self._damage_since(reported)
                    reported = len(self.damage)
                    if feed.lineno == started:  # not a line's fault: the header's
                        yield self.unreadable(exc)
                        return
                    yield self.bad_line(feed.lineno, feed.last, exc)
                    feed.restart(self._replay())
                    break
                yield msg
                if reported < len(self.damage):
                    yield from self._damage_since(reported)
                    reported = len(self.damage)

    def _damage_since(self, reported: int) -> Iterator[Event]:
        for problem in self.damage[reported:]:
            yield damage_after_line(self.source, self.last_time, self.feed.lineno, problem)

    def unreadable(self, exc: BaseException) -> Event:
        why = str(exc).strip().splitlines()
        reason = f"{type(exc).__name__}: {why[0]}" if why else type(exc).__name__
        return diagnostic(
            self.last_time,
            self.source,
            BAD_LINE,
            f"reading stopped after line {self.feed.lineno}: {reason}",
            line=self.feed.lineno,
        )

    def bad_line(self, lineno: int, line: str, exc: BaseException) -> Event:
        self.bad_lines += 1
        shown = line.rstrip("\r\n")
        text = shown if len(shown) <= 60 else shown[:57] + "..."
        why = str(exc).strip().splitlines()
        reason = f"{type(exc).__name__}: {why[0]}" if why else type(exc).__name__
        if isinstance(exc, SkippedLine):
            reason = str(exc)
        if len(line) >= MAX_LINE:
            reason = f"line longer than {MAX_LINE:,} bytes"
        return diagnostic(
            self.last_time,
            self.source,
            BAD_LINE,
            f"line {lineno}: not a {self.fmt.upper()} frame ({reason}): {text!r}",
            shown[:RAW_LIMIT].encode("utf-8", "replace"),
            line=lineno,
        )


def _chain(first: list[str], rest: Iterator[str]) -> Iterator[str]:
    yield from first
    yield from rest
