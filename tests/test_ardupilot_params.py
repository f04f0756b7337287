"""The driver's parameters are written once (analyzer/export/ardupilot_params.py): the Lua
parameter block, the @Param documentation ArduPilot's tools read, the usage text, the
driver's page and the manual all say the same, and the driver uses no other."""

from __future__ import annotations

import re
from pathlib import Path

from analyzer.ardupilot.script import LuaScript
from analyzer.ardupilot.vehicle import SETUP_PARAMETERS, Vehicle
from analyzer.export.ardupilot import DRIVER_NAME, lua_text, markdown_text
from analyzer.export.ardupilot_params import (
    AUTOPILOT_PARAMETERS,
    PARAM_TABLE_KEY,
    PARAM_TABLE_PREFIX,
    PARAMETERS,
)

ROOT = Path(__file__).resolve().parents[1]
MANUAL = ROOT / "docs" / "howto" / "ardupilot.md"


def param_blocks(text: str) -> dict[str, dict[str, str]]:
    """The @Param blocks of a Lua script, as ArduPilot's param_parse reads them."""
    blocks: dict[str, dict[str, str]] = {}
    for block in re.findall(r"--\[\[(.*?)--\]\]", text, flags=re.S):
        tags = dict(re.findall(r"// @(\w+): (.*)", block))
        if "Param" in tags:
            blocks[tags.pop("Param")] = tags
    return blocks


def test_the_lua_block_adds_and_documents_each_parameter_once() -> None:
    text = lua_text()
    assert f"param:add_table(PARAM_TABLE_KEY, PARAM_TABLE_PREFIX, {len(PARAMETERS)})" in text
    added = re.findall(r'param:add_param\(PARAM_TABLE_KEY, (\d+), "(\w+)", ([\d.]+)\)', text)
    assert added == [(str(n), p.name, str(p.default)) for n, p in enumerate(PARAMETERS, 1)]
    blocks = param_blocks(text)
    assert list(blocks) == [p.full_name for p in PARAMETERS]
    for p in PARAMETERS:
        tags = blocks[p.full_name]
        assert tags["DisplayName"] == p.display_name and tags["Description"] == p.description
        assert tags["User"] == p.user
        if p.values:
            assert tags["Values"] == ",".join(f"{v}:{what}" for v, what in p.values)
        if p.limits:
            assert tags["Range"] == f"{p.limits[0]} {p.limits[1]}"
        assert f'local {p.full_name} = Parameter("{p.full_name}")' in text
    used = set(re.findall(rf"\b{PARAM_TABLE_PREFIX}\w+", re.sub(r"--.*", "", text)))
    assert used == {p.full_name for p in PARAMETERS}  # the body reads no other


def test_the_autopilot_gets_the_parameters_with_their_defaults() -> None:
    vehicle = Vehicle(lambda *_: True)
    LuaScript(lua_text(), DRIVER_NAME, vehicle).start(1000)
    table = vehicle.tables[PARAM_TABLE_KEY]
    assert (table.prefix, table.size) == (PARAM_TABLE_PREFIX, len(PARAMETERS))
    assert list(table.names.values()) == [p.full_name for p in PARAMETERS]
    for p in PARAMETERS:
        assert vehicle.parameters[p.full_name] == p.default


def test_the_usage_text_the_page_and_the_manual_say_the_same() -> None:
    header = lua_text().split("--]]")[0]
    page = markdown_text()
    manual = MANUAL.read_text(encoding="utf-8")
    rows = dict(re.findall(r"^\| `(\w+)` \| ([^|]+?) \|", manual, flags=re.M))
    for p in PARAMETERS:
        assert f"    {p.full_name} {p.usage}" in header
        assert f"## {p.full_name}\n\n{p.description} (default {p.default})." in page
        assert rows[p.full_name] == str(p.default), p.full_name
    for p in AUTOPILOT_PARAMETERS:
        note = f" {p.note}" if p.note else ""
        assert f"    Set {p.name} = {p.value}{note}: {p.why}" in header
        assert f"| {p.name} | {p.value}{note} | {p.why} |" in page
        assert rows[p.name] == f"{p.value}{note}", p.name
        assert SETUP_PARAMETERS[p.name] == p.value, p.name  # the emulated autopilot's
    assert f"table key {PARAM_TABLE_KEY}, prefix `{PARAM_TABLE_PREFIX}`" in manual
