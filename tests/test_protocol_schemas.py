"""The JSON Schemas and the protocol reference are generated from the tables, never by hand."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema

from analyzer.commands.schemas import rendered
from analyzer.protocol.docs import command_reference
from analyzer.protocol.schema import topic_schemas
from analyzer.protocol.types import TOPICS

ROOT = Path(__file__).resolve().parent.parent


def test_checked_in_schemas_match_the_table() -> None:
    files = rendered()
    assert sorted(files) == sorted(p.name for p in (ROOT / "schemas").glob("*.schema.json"))
    for name, text in files.items():
        assert (ROOT / "schemas" / name).read_text(encoding="utf-8") == text, (
            f"schemas/{name} is out of date: run `gimbal-analyzer schemas`"
        )


def test_one_valid_schema_per_topic() -> None:
    schemas = topic_schemas()
    assert set(schemas) == set(TOPICS)
    for schema in schemas.values():
        jsonschema.Draft202012Validator.check_schema(schema)
        json.dumps(schema)


def test_command_schema_lists_every_command_name_and_field() -> None:
    from analyzer.protocol.command_table import COMMANDS

    schema = topic_schemas()["/gimbal/command"]
    assert set(schema["properties"]["name"]["enum"]) == {c.name for c in COMMANDS} | {"unknown"}
    for row in COMMANDS:
        for f in row.all_fields():
            assert f.name in schema["properties"], f.name


def test_the_markdown_reference_names_every_command_and_message() -> None:
    """`commands --markdown` and the manual's protocol page come from one generator."""
    from analyzer.protocol.command_table import COMMANDS
    from analyzer.protocol.feedback import LAYOUTS
    from analyzer.protocol.uav import STATUS_FRAMES

    text = command_reference()
    for row in COMMANDS:
        assert f"| 0x{row.cmd:02X} | `{row.name}` | {row.title} |" in text, row.name
    for layout in LAYOUTS.values():
        assert f"### {layout.name} (length byte 0x{layout.length_byte:02X}" in text
    for status in STATUS_FRAMES.values():
        assert f"### {status.name} (CAN ID 0x{status.can_id:08X}" in text
