"""One pass over an input file for `replay` and `compare`: read and decoded as `decode` does."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any

from analyzer.input_options import check_port
from analyzer.pipeline import Sink, Stage


def read_through(
    path: str,
    sinks: Sequence[Sink],
    *,
    stages: Sequence[Stage] = (),
    file_format: str | None = None,
    port: int = 2000,
    quiet: bool = False,
    label: str = "",
) -> Any:
    """Decode ``path`` (anything `decode` reads) through ``stages`` into ``sinks``, with
    a progress line on a terminal (not with ``quiet``); returns the reader (its
    ``format_name``, ``notes``). A sink that failed raises its error."""
    from analyzer.api.reading import open_decoding
    from analyzer.pipeline import run_reader
    from analyzer.progress import Progress

    check_port(port)
    decoding = open_decoding(path, file_format, port=port)
    reader, pipeline = decoding.reader, decoding.pipeline
    pipeline.stages.extend(stages)
    pipeline.sinks.extend(sinks)
    progress = Progress.maybe(reader, sys.stderr, quiet=quiet, label=label)
    run_reader(reader, pipeline, batch_items=decoding.batch_items, progress=progress)
    return reader
