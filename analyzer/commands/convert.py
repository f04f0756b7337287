"""`gimbal-analyzer convert`: any capture file `decode` reads, as an MCAP recording."""

from __future__ import annotations

import argparse
import os
import sys
import time

from analyzer.errors import EXIT_INTERRUPTED, UsageError
from analyzer.mcapio.write.options import add_compression_argument
from analyzer.pipeline import Pipeline, run_reader
from analyzer.progress import Progress
from analyzer.stdio import interrupt_name, interrupts_deferred

HELP = "convert a capture file (candump, python-can logs, pcap, raw dumps, MCAP) to MCAP"
DESCRIPTION = """\
Decode a capture file and write an MCAP recording of it: the same channels as
`record` (decoded events, the raw frames / bytes, Foxglove map and log views).
Any input `decode` accepts works; an MCAP input is decoded again from its raw
channels, so an old recording gets the fixes of a newer decoder.

The output is written under a temporary name in the same directory and
renamed when complete: an existing file is replaced only with --force (never
the input itself), and a failed conversion (a full disk, Ctrl-C, SIGTERM) leaves no
partial file behind.

  gimbal-analyzer convert flight.log -o flight.mcap
  gimbal-analyzer convert capture.pcap -o capture.mcap --port 2000
  gimbal-analyzer convert uart.bin -o uart.mcap --format raw
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("input", help="capture file")
    parser.add_argument("-o", "--output", required=True, metavar="FILE", help="MCAP file to write")
    parser.add_argument(
        "--format", metavar="F", help="input format (default: detected from the file)"
    )
    parser.add_argument(
        "--port", type=int, metavar="N", help="pcap inputs: TCP port of the IDU (default 2000)"
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress, no summary")
    add_compression_argument(parser)
    parser.add_argument(
        "-f",
        "--force",
        action="store_true",
        help="replace an existing output file (never the input, never a symlink)",
    )


def run(args: argparse.Namespace) -> int:
    from analyzer.inputs import open_input
    from analyzer.mcapio.write.sink import McapSink, recording_metadata
    from analyzer.output_file import check_output

    if args.input != "-" and not os.path.exists(args.input):
        raise UsageError(f"no such file: {args.input}")
    inputs = [] if args.input == "-" else [args.input]
    target = check_output(args.output, force=args.force, inputs=inputs)
    from analyzer.protocol.ids import TCP_PORT

    source = open_input(args.input, args.format, TCP_PORT if args.port is None else args.port)
    meta = recording_metadata(
        f"file:{args.input}", command="convert", input_format=args.format or "auto"
    )
    from analyzer.analysis.stage import Analysis

    # Made before the output exists: the decoder's import takes a while. A recording with
    # video has its camera commands judged from it too.
    notes: list[str] = []  # the camera not judged: the video extra is missing
    pipeline = Pipeline(stages=Analysis.of_file(args.input).tell(notes.append).stages())
    progress = Progress.maybe(source, sys.stderr, quiet=args.quiet, label="converting ")
    started = time.perf_counter()
    sink: McapSink | None = None
    finished = False
    interrupted = ""
    try:
        with interrupts_deferred():  # a signal now would leave a file nobody removes
            sink = McapSink(
                target,
                metadata=meta,
                flush_interval=None,
                force=args.force,
                inputs=inputs,
                atomic=True,
                compression=args.compression,
            )
        pipeline.sinks.append(sink)
        run_reader(source, pipeline, progress=progress)  # closes (commits) the sink
        finished = True
    except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM: the finally removes the partial file
        interrupted = interrupt_name(exc)
    finally:
        source.close()  # closed by the run too; here also when no output could be made
        if not finished and sink is not None:
            sink.abandon()
    if interrupted:
        print(
            f"gimbal-analyzer convert: interrupted ({interrupted}): {target} was not written "
            "(the unfinished output was removed)",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    for note in [*getattr(source, "notes", ()), *notes]:
        print(f"note: {note}", file=sys.stderr)
    if sink is not None and sink.retimed_input:
        print(
            f"note: the input goes back in time: {sink.retimed_input} message(s) older than data "
            "already written got that data's time as MCAP log time (their own time stays in "
            "the message)",
            file=sys.stderr,
        )
    if not args.quiet:
        tally = pipeline.tally
        seconds = time.perf_counter() - started
        items = tally.frames + tally.chunks
        rate = items / seconds if seconds > 0 else 0.0
        print(
            f"converted {tally.frames} CAN frames and {tally.chunks} stream chunks "
            f"({tally.events} events, {tally.diagnostics} diagnostics) to {target} "
            f"in {seconds:.1f} s ({rate:,.0f} items/s)",
            file=sys.stderr,
        )
    return 0
