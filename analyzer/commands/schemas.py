"""`gimbal-analyzer schemas`: write or check the JSON Schema of every topic."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from analyzer.errors import UsageError

HELP = "write (or --check) the JSON Schemas of every topic into a directory"
DESCRIPTION = """\
The JSON Schemas are generated from the protocol table. This writes one file
per topic (e.g. gimbal.command.schema.json) into DIR (default: schemas).

  gimbal-analyzer schemas            write schemas/*.schema.json
  gimbal-analyzer schemas --check    exit 1 if the files differ from the table
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("directory", nargs="?", default="schemas", help="output directory")
    parser.add_argument("--check", action="store_true", help="only compare, write nothing")


def rendered() -> dict[str, str]:
    """File name -> file text for every topic."""
    from analyzer.protocol.schema import schema_filename, topic_schemas

    return {
        schema_filename(topic): json.dumps(schema, indent=2) + "\n"
        for topic, schema in topic_schemas().items()
    }


def run(args: argparse.Namespace) -> int:
    directory = Path(args.directory)
    files = rendered()
    if args.check:
        from analyzer.mcapio.schema_subset import foxglove_problems

        refused = [
            f"{path.name}: {problem}"
            for path in sorted(directory.glob("*.schema.json"))
            for problem in foxglove_problems(_load(path), path.name)
        ]
        if refused:
            print(f"Foxglove would refuse schemas in {directory}: " + "; ".join(refused))
            return 1
        stale = [
            name
            for name, text in files.items()
            if not (directory / name).is_file()
            or (directory / name).read_text(encoding="utf-8") != text
        ]
        if stale:
            print(f"out of date in {directory}: {', '.join(stale)} (run: gimbal-analyzer schemas)")
            return 1
        print(
            f"{len(files)} schemas in {directory} match the protocol table "
            "and are in the JSON Schema subset Foxglove reads"
        )
        return 0
    try:
        directory.mkdir(parents=True, exist_ok=True)
        for name, text in files.items():
            (directory / name).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise UsageError(f"cannot write schemas to {directory}: {exc.strerror}") from None
    print(f"wrote {len(files)} schemas to {directory}")
    return 0


def _load(path: Path) -> object:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        return f"unreadable: {exc}"
