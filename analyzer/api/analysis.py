"""``analyze``: did the gimbal obey? The findings of ``analyze --json``, in time order."""

from __future__ import annotations

import os
import warnings
from collections.abc import Generator, Iterable
from dataclasses import dataclass

from analyzer.analysis.findings import Timed, untimed
from analyzer.analysis.settings import (
    DEFAULT_FLAG_ALLOWED_S,
    DEFAULT_TIME_ALLOWED_S,
    DEFAULT_TOLERANCE_DEG,
    Settings,
)
from analyzer.analysis.stage import WITHOUT_VIDEO, Analysis, Judging
from analyzer.analysis.time_order import TimeOrder
from analyzer.api.reading import (
    Closable,
    Decoding,
    FileEvents,
    Path,
    input_errors,
    open_decoding,
)
from analyzer.pipeline import BATCH_ITEMS, Pipeline, delivered_batches
from analyzer.protocol.ids import TCP_PORT
from analyzer.protocol.types import Event

__all__ = ["Finding", "Findings", "FindingsInOrder", "Judging", "analyze"]


@dataclass(slots=True)
class Finding(Event):
    """One judgement of the response analysis (topic ``/analysis/response``): ``command``
    judged, by which ``check`` (target, rate, repeat, stop, tracking, limit, feedback,
    ...), its ``verdict`` and a ``detail`` in words; ``time`` is the command's time and
    ``fields`` hold the numbers (``target_deg``, ``error_deg``, ``response_s``, ...).
    ``to_dict()`` is the line ``analyze --json`` prints (schema:
    ``schemas/analysis.response.schema.json``).

    >>> from analyzer import analyze
    >>> finding = next(analyze("samples/flight-candump.log"))
    >>> finding.topic, finding.source
    ('/analysis/response', 'analysis')
    >>> finding.verdict == finding.to_dict()["verdict"] and finding.detail != ""
    True
    """

    @property
    def command(self) -> str:
        return str(self.fields.get("command", ""))

    @property
    def check(self) -> str:
        return str(self.fields.get("check", ""))

    @property
    def verdict(self) -> str:
        return str(self.fields.get("verdict", ""))

    @property
    def detail(self) -> str:
        return str(self.fields.get("detail", ""))

    @classmethod
    def of(cls, event: Event) -> Finding:
        return cls(event.topic, event.time, event.source, event.fields, event.warnings)


class FindingsInOrder:
    """The response analysis as a pipeline stage whose findings come out in time order.

    As a stage it hands on the findings it makes (and no finding the input already
    holds) and keeps them; after each delivered batch ``ready()`` gives those no finding
    still to come can precede, so what is held is what the pending judgements span, not
    the flight. An input without a clock (a raw byte dump: every time the same) gets no
    findings: ``ready()`` gives none until the times are seen to differ, and ``rest()``
    at the end gives none and sets ``untimed``. ``analyze`` (the command and the
    Python API) runs this.
    """

    def __init__(self, analysis: Judging, tally: Timed) -> None:
        self.analysis = analysis
        self.tally = tally
        self.order: TimeOrder[Event] = TimeOrder()
        self.found = 0
        self.untimed = False

    def process(self, events: list[Event]) -> list[Event]:
        return self._held(self.analysis.process(events))

    def close(self) -> list[Event]:
        return self._held(self.analysis.close())

    def ready(self) -> list[Event]:
        """After a delivered batch: the findings no finding still to come can precede."""
        if untimed(self.tally, [True]):
            return []
        return self.order.release(self.analysis.earliest_pending())

    def rest(self) -> list[Event]:
        """After the last batch: every finding still held (none for an input without a
        clock, then ``untimed`` is set)."""
        self.untimed = untimed(self.tally, [True] if self.found else [])
        if self.untimed:
            self.order.clear()
            return []
        return self.order.drain()

    def _held(self, findings: list[Event]) -> list[Event]:
        for event in findings:
            self.found += 1
            self.order.push(event.time, event)
        return findings


class Findings(Closable[Finding]):
    """What ``analyze`` gives: its findings one at a time, as they are decided.

    ``camera_judged`` says whether the camera commands were judged from the recording's
    video; when they could have been and were not, ``camera_note`` says why, in one line:
    the video extra is not installed, or the events came without their video (an iterable
    of ``Event``s other than ``read``'s: a ``Decoder``'s, a ``Listener``'s, a list)."""

    def __init__(self, findings: Generator[Finding, None, None], analysis: Analysis) -> None:
        super().__init__(findings)
        self.camera_judged = analysis.judges_camera
        self.camera_note = analysis.camera_note


def analyze(
    source: Path | Iterable[Event],
    *,
    tolerance_deg: float = DEFAULT_TOLERANCE_DEG,
    time_allowed_s: float = DEFAULT_TIME_ALLOWED_S,
    flag_allowed_s: float = DEFAULT_FLAG_ALLOWED_S,
    format: str | None = None,
    port: int = TCP_PORT,
) -> Findings:
    """Did the gimbal obey? Each command with a visible effect judged against the
    attitude feedback that followed, and the feedback's own health: the findings of
    ``analyze --json``, in time order, as they are decided.

    ``source`` is a capture file or recording (anything ``read`` reads; ``format`` and
    ``port`` as there) or an iterable of ``Event``s (from ``read``, a ``Decoder``, a
    ``Listener``, ``Recording.events``). The options are the command's:
    ``tolerance_deg`` (``--tolerance``: this close to a target counts as reached),
    ``time_allowed_s`` (``--time-allowed``: for a target to be reached),
    ``flag_allowed_s`` (``--flag-allowed``: for the tracking flag to change); a value
    that is not above 0 raises ``ValueError``. An input without a clock (a raw byte
    dump) gives no findings. Errors of the input as ``read``.

    The camera commands of a recording with video (``demo --video``, ``record --video``)
    are judged from its pictures, whether ``source`` is the recording's path or
    ``read(path)`` (its events know their file); without the video extra they are not,
    and a ``RuntimeWarning`` says so. Events that came without their video (a
    ``Decoder``'s, a ``Listener``'s, a list) leave the camera commands unjudged: the
    result's ``camera_judged`` is False and ``camera_note`` says why.

    >>> from analyzer import analyze, read
    >>> findings = list(analyze("samples/flight-candump.log", tolerance_deg=2))
    >>> [f.command for f in findings if f.check == "target"]
    ['specified_angle', 'specified_angle', 'look_down', 'forward']
    >>> findings == list(analyze(read("samples/flight-candump.log"), tolerance_deg=2))
    True
    >>> analyze([]).camera_note
    'camera commands not judged: the events came without their video'
    """
    settings = Settings(
        tolerance_deg=tolerance_deg, time_allowed_s=time_allowed_s, flag_allowed_s=flag_allowed_s
    )
    if isinstance(source, (str, os.PathLike)):
        with input_errors(source):
            decoding = open_decoding(source, format, port=port)
        analysis = Analysis.of_file(source, settings).tell(_warn)
        return Findings(_read_findings(decoding, analysis, source), analysis)
    if isinstance(source, FileEvents):  # read(path): the file's video judges its camera
        analysis = Analysis.of_file(source.path, settings).tell(_warn)
    else:
        analysis = Analysis(settings, camera_note=WITHOUT_VIDEO)
    return Findings(_findings(source, Pipeline(), analysis.judging(), BATCH_ITEMS), analysis)


def _read_findings(
    decoding: Decoding, analysis: Analysis, path: Path
) -> Generator[Finding, None, None]:
    """The findings of an opened input; its reader is closed at the end (or when the
    caller stops early)."""
    try:
        with input_errors(path):
            yield from _findings(
                decoding.reader, decoding.pipeline, analysis.judging(), decoding.batch_items
            )
    finally:
        decoding.reader.close()


def _warn(note: str) -> None:
    """A library's way of saying something was left out (the camera, without the video
    extra): a warning the caller sees once, and may turn into an error."""
    warnings.warn(note, RuntimeWarning, stacklevel=4)


def _findings(
    items: Iterable[object], pipeline: Pipeline, judging: Judging, batch_items: int
) -> Generator[Finding, None, None]:
    """The pipeline of ``analyze`` run over ``items``, its findings as they are released."""
    findings = FindingsInOrder(judging, pipeline.tally)
    pipeline.stages.append(findings)
    for _ in delivered_batches(items, pipeline, batch_items=batch_items):
        yield from map(Finding.of, findings.ready())
    yield from map(Finding.of, findings.rest())
