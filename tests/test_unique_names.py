"""One name, one thing: every class name is defined once in analyzer/, and the protocol's
facts are defined in protocol/ only (the other layers import them from there)."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import analyzer

PACKAGE = Path(__file__).resolve().parents[1] / "analyzer"
# Facts of the protocol that other layers once kept copies of.
PROTOCOL_FACTS = ("WIDE_MOTOR_YAW_TYPES", "MOTOR_YAW_LIMIT", "GIMBAL_TYPES", "CONTROL_MODES")


def classes_by_name(root: Path) -> dict[str, list[str]]:
    """Class name -> where each class of that name is defined (``path:line``)."""
    found: dict[str, list[str]] = defaultdict(list)
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                found[node.name].append(f"{path.relative_to(root.parent)}:{node.lineno}")
    return found


def test_every_class_name_is_defined_once_in_the_package() -> None:
    twice = {name: places for name, places in classes_by_name(PACKAGE).items() if len(places) > 1}
    assert not twice, (
        "class names defined more than once (give the internal one a name that says what it is): "
        + "; ".join(f"{name} in {', '.join(places)}" for name, places in sorted(twice.items()))
    )


def test_the_check_finds_a_name_defined_twice(tmp_path: Path) -> None:
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "a.py").write_text("class Decoder:\n    pass\n", encoding="utf-8")
    (package / "b.py").write_text("def f():\n    class Decoder: ...\n", encoding="utf-8")
    assert classes_by_name(package)["Decoder"] == ["pkg/a.py:1", "pkg/b.py:2"]


def test_the_public_names_keep_their_names() -> None:
    public_classes = {"Decoder", "Event", "Finding", "Listener", "Recording"}
    places = classes_by_name(PACKAGE)
    for name in public_classes:
        assert name in analyzer.__all__
        (place,) = places[name]
        assert place.startswith(("analyzer/api/", "analyzer/protocol/types.py")), place


def test_protocol_facts_are_defined_in_protocol_only() -> None:
    outside = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.relative_to(PACKAGE).parts[0] == "protocol":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in ast.walk(tree):
            targets = node.targets if isinstance(node, ast.Assign) else []
            if isinstance(node, ast.AnnAssign):
                targets = [node.target]
            outside += [
                f"{path.relative_to(PACKAGE.parent)}:{node.lineno} {t.id}"
                for t in targets
                if isinstance(t, ast.Name) and t.id in PROTOCOL_FACTS
            ]
    assert not outside, f"protocol facts defined outside protocol/: {outside}"
