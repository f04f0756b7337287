"""Output files: no silent overwrite, never over an input, never through a planted symlink."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from analyzer import output_file
from analyzer.cli import main
from analyzer.commands import demo
from analyzer.mcapio.read.reader import McapRecording
from analyzer.output_file import OutputFile, OutputRefused, check_output, write_output
from tests.platforms import posix_permissions, symlinks

CANDUMP = "".join(f"({1715680800 + n * 0.01:.6f}) can0 0F01#0F040CFE00000000\n" for n in range(50))


def _listing(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_a_new_file_appears_only_when_committed(tmp_path: Path) -> None:
    target = tmp_path / "out.bin"
    out = OutputFile(target)
    out.file.write(b"data")  # type: ignore[arg-type]
    assert not target.exists()
    temp = Path(out.written_path)
    assert temp.parent == tmp_path and temp.name.startswith(".out.bin.") and temp.exists()
    out.commit()
    assert target.read_bytes() == b"data"
    assert _listing(tmp_path) == ["out.bin"]


def test_a_failure_inside_the_block_leaves_nothing(tmp_path: Path) -> None:
    with pytest.raises(RuntimeError), OutputFile(tmp_path / "out.txt", encoding="utf-8") as out:
        out.file.write("half")  # type: ignore[arg-type]
        raise RuntimeError("boom")
    assert _listing(tmp_path) == []


def test_an_existing_file_is_replaced_only_with_force(tmp_path: Path) -> None:
    target = tmp_path / "out.txt"
    target.write_text("precious", encoding="utf-8")
    with pytest.raises(OutputRefused, match="use --force"):
        write_output(target, "new")
    assert target.read_text(encoding="utf-8") == "precious"
    write_output(target, "new", force=True)
    assert target.read_text(encoding="utf-8") == "new"
    assert _listing(tmp_path) == ["out.txt"]


@posix_permissions
def test_the_new_file_gets_the_usual_permissions(tmp_path: Path) -> None:
    old = os.umask(0o022)
    try:
        write_output(tmp_path / "a.txt", "x")
        out = OutputFile(tmp_path / "b.mcap", atomic=False)
        out.close_keep()
    finally:
        os.umask(old)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644
    assert (tmp_path / "b.mcap").stat().st_mode & 0o777 == 0o644


@pytest.mark.parametrize("dangling", [True, False])
@pytest.mark.parametrize("force", [True, False])
@pytest.mark.parametrize("atomic", [True, False])
@symlinks
def test_a_symlink_at_the_output_is_never_followed(
    tmp_path: Path, dangling: bool, force: bool, atomic: bool
) -> None:
    victim = tmp_path / "victim.txt"
    if not dangling:
        victim.write_text("precious", encoding="utf-8")
    link = tmp_path / "out.mcap"
    link.symlink_to(victim)
    with pytest.raises(OutputRefused, match="symbolic link"):
        OutputFile(link, force=force, atomic=atomic)
    assert link.is_symlink()
    assert victim.exists() is not dangling
    if not dangling:
        assert victim.read_text(encoding="utf-8") == "precious"


def test_the_output_may_never_be_an_input_even_with_force(tmp_path: Path) -> None:
    source = tmp_path / "flight.log"
    source.write_text("x", encoding="utf-8")
    alias = tmp_path / "alias.log"
    os.link(source, alias)  # the same file under another name
    for name in (source, alias):
        with pytest.raises(OutputRefused, match="overwrite the input"):
            check_output(name, force=True, inputs=[source])
    assert source.read_text(encoding="utf-8") == "x"


@symlinks
def test_a_file_planted_while_writing_is_kept_and_so_is_the_output(tmp_path: Path) -> None:
    target = tmp_path / "out.txt"
    out = OutputFile(target, encoding="utf-8")
    out.file.write("ours")  # type: ignore[arg-type]
    target.symlink_to(tmp_path / "elsewhere")
    with pytest.raises(OutputRefused, match="appeared while it was being written"):
        out.commit()
    assert target.is_symlink() and not (tmp_path / "elsewhere").exists()
    assert Path(out.written_path).read_text(encoding="utf-8") == "ours"


@symlinks
def test_a_direct_output_refuses_a_name_taken_after_the_check(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = tmp_path / "rec.mcap"
    checked = output_file.check_output

    def check_then_plant(*args: object, **kwargs: object) -> Path:
        result = checked(*args, **kwargs)  # type: ignore[arg-type]
        target.symlink_to(tmp_path / "victim")
        return result

    monkeypatch.setattr(output_file, "check_output", check_then_plant)
    with pytest.raises(OutputRefused, match="appeared"):
        OutputFile(target, atomic=False)
    assert not (tmp_path / "victim").exists()


def test_discard_removes_only_our_own_file(tmp_path: Path) -> None:
    target = tmp_path / "rec.mcap"
    out = OutputFile(target, atomic=False)
    out.discard()
    assert not target.exists()
    out = OutputFile(target, atomic=False)
    os.unlink(target)
    target.write_text("someone else's", encoding="utf-8")
    out.discard()
    assert target.read_text(encoding="utf-8") == "someone else's"


# -- the commands -------------------------------------------------------------------------------


@symlinks
def test_convert_needs_force_and_ignores_a_planted_partial_symlink(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "flight.log"
    log.write_text(CANDUMP, encoding="utf-8")
    out = tmp_path / "flight.mcap"
    victim = tmp_path / "victim.txt"
    victim.write_text("precious", encoding="utf-8")
    (tmp_path / "flight.mcap.partial").symlink_to(victim)  # the old predictable temp name
    assert main(["convert", str(log), "-o", str(out), "-q"]) == 0
    assert victim.read_text(encoding="utf-8") == "precious"
    first = out.read_bytes()
    assert main(["convert", str(log), "-o", str(out), "-q"]) == 2
    assert "use --force" in capsys.readouterr().err
    assert out.read_bytes() == first
    assert main(["convert", str(log), "-o", str(out), "-q", "--force"]) == 0
    assert McapRecording(out).metadata()  # a complete recording
    assert _listing(tmp_path) == ["flight.log", "flight.mcap", "flight.mcap.partial", "victim.txt"]


@symlinks
def test_convert_refuses_a_symlinked_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "flight.log"
    log.write_text(CANDUMP, encoding="utf-8")
    (tmp_path / "out.mcap").symlink_to(tmp_path / "nowhere.mcap")
    assert main(["convert", str(log), "-o", str(tmp_path / "out.mcap"), "--force"]) == 2
    assert "symbolic link" in capsys.readouterr().err
    assert not (tmp_path / "nowhere.mcap").exists()


def test_record_never_overwrites_its_own_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "X.log"
    log.write_text(CANDUMP, encoding="utf-8")
    code = main(["record", "--source", f"file:{log}", "-o", str(log), "--force", "-q"])
    assert code == 2
    assert "overwrite the input" in capsys.readouterr().err
    assert log.read_text(encoding="utf-8") == CANDUMP


@symlinks
def test_record_does_not_follow_a_dangling_symlink(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "X.log"
    log.write_text(CANDUMP, encoding="utf-8")
    out = tmp_path / "rec.mcap"
    out.symlink_to(tmp_path / "planted.mcap")
    assert main(["record", "--source", f"file:{log}", "-o", str(out), "-q"]) == 2
    assert "symbolic link" in capsys.readouterr().err
    assert not (tmp_path / "planted.mcap").exists()


def test_record_force_replaces_an_earlier_recording(tmp_path: Path) -> None:
    log = tmp_path / "X.log"
    log.write_text(CANDUMP, encoding="utf-8")
    out = tmp_path / "rec.mcap"
    out.write_bytes(b"old")
    assert main(["record", "--source", f"file:{log}", "-o", str(out), "-q"]) == 2
    assert out.read_bytes() == b"old"
    assert main(["record", "--source", f"file:{log}", "-o", str(out), "-q", "--force"]) == 0
    assert sum(1 for _ in McapRecording(out).messages()) > 0
    assert _listing(tmp_path) == ["X.log", "rec.mcap"]


def test_demo_replaces_only_a_recording_it_wrote_itself(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    foreign = tmp_path / "demo.mcap"
    foreign.write_bytes(b"someone's notes")
    assert main(["demo", "--no-tui", "--duration", "0.3", "--clean"]) == 2
    assert "use --force" in capsys.readouterr().err
    assert foreign.read_bytes() == b"someone's notes"
    foreign.unlink()
    assert main(["demo", "--no-tui", "--duration", "0.3", "--clean"]) == 0
    assert demo.written_by_demo(foreign)
    first = foreign.read_bytes()
    assert main(["demo", "--no-tui", "--duration", "0.3", "--clean"]) == 0  # its own: replaced
    assert foreign.read_bytes() != first
    capsys.readouterr()
