"""The JSON Schema subset Foxglove reads: a schema outside it makes Foxglove drop the topic."""

from __future__ import annotations

from typing import Any

# Foxglove's reader (parseJsonSchema of @foxglove/mcap-support, also used by Lichtblick) turns
# a JSON Schema into message definitions. Per property it accepts exactly one ``type`` of
# these; a type list (["number", "null"]), "null" or a missing type is an error that makes
# it refuse the whole channel. ``oneOf`` is accepted only when every alternative has a
# numeric ``const`` (an enumeration); the reader then ignores ``type``. Keywords it does not
# read (description, enum, pattern, minimum, required, ...) are free.
SCALAR_TYPES = ("boolean", "string", "number", "integer")
ITEM_TYPES = (*SCALAR_TYPES, "object")


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def foxglove_problems(schema: Any, name: str = "schema") -> list[str]:
    """What Foxglove would refuse in ``schema`` (empty when it reads it)."""
    problems: list[str] = []
    _object(schema, name, [], problems)
    return problems


def _object(schema: Any, type_name: str, path: list[str], problems: list[str]) -> None:
    where = ".".join(path) or type_name
    if not isinstance(schema, dict) or schema.get("type") != "object":
        got = schema.get("type") if isinstance(schema, dict) else schema
        problems.append(f'{where}: expected "type": "object", got {got!r}')
        return
    properties = schema.get("properties")
    if not isinstance(properties, dict):
        problems.append(f"{where}: an object needs a 'properties' object")
        return
    for field_name, field in properties.items():
        _property(field, field_name, f"{type_name}.{field_name}", [*path, field_name], problems)


def _property(
    field: Any, field_name: str, type_name: str, path: list[str], problems: list[str]
) -> None:
    where = ".".join(path)
    if not isinstance(field, dict):
        problems.append(f"{where}: a property schema must be an object, got {field!r}")
        return
    one_of = field.get("oneOf")
    if isinstance(one_of, list):
        for alternative in one_of:
            if not isinstance(alternative, dict) or not _is_number(alternative.get("const")):
                problems.append(f"{where}: oneOf alternatives must have number values")
                return
            if not isinstance(alternative.get("title"), str):
                problems.append(f"{where}: every oneOf alternative needs a 'title' (its name)")
                return
        return
    kind = field.get("type")
    if kind in ("boolean", "number", "integer"):
        return
    if kind == "string":
        encoding = field.get("contentEncoding")
        if encoding not in (None, "base64"):
            problems.append(f"{where}: unsupported contentEncoding {encoding!r}")
        return
    if kind == "object":
        _object(field, type_name, path, problems)
        return
    if kind == "array":
        items = field.get("items")
        if not isinstance(items, dict):
            problems.append(f"{where}: an array needs an 'items' schema object")
            return
        item_kind = items.get("type")
        if item_kind == "string" and items.get("contentEncoding") is not None:
            problems.append(f"{where}: unsupported contentEncoding for array items")
        elif item_kind == "object":
            _object(items, type_name, path, problems)
        elif item_kind not in SCALAR_TYPES:
            problems.append(f"{where}: unsupported type {item_kind!r} for array items")
        return
    problems.append(f"{where}: unsupported type {kind!r}")
