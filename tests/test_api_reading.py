"""The Python API's readers against the command line: ``read`` is ``decode --json``,
``analyze`` is ``analyze --json``, ``Recording`` is ``decode --stored`` and ``table``."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow as pa
import pytest

from analyzer import Event, Recording, analyze, read
from analyzer.fleet.columns import TOPIC_TABLES
from tests.fault_logs import CANDUMP_NAME, STREAM_NAME, write_fault_logs
from tests.fleet_flights import cli_output, rows

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "samples"


def lines(events: object) -> list[str]:
    """Events (or findings) as the command line prints them with --json."""
    assert not isinstance(events, list) or all(isinstance(e, Event) for e in events)
    return [json.dumps(e.to_dict(), default=str) for e in events]  # type: ignore[attr-defined]


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The samples, the fault logs, and recordings converted from two of them."""
    folder = tmp_path_factory.mktemp("api-inputs")
    found = {p.name: p for p in sorted(SAMPLES.iterdir()) if p.suffix != ".md"}
    found.update({p.name: p for p in write_fault_logs(folder)})
    for name in ("flight-candump.log", CANDUMP_NAME):
        mcap = folder / (Path(name).stem + ".mcap")
        cli_output("convert", str(found[name]), "-o", str(mcap), "-q")
        found[mcap.name] = mcap
    return found


NAMES = ["flight-candump.log", "idu-tcp.pcap", "uart-dump.bin", CANDUMP_NAME, STREAM_NAME,
         "flight-candump.mcap"]  # fmt: skip


@pytest.mark.parametrize("name", NAMES)
def test_read_gives_the_events_decode_json_prints(inputs: dict[str, Path], name: str) -> None:
    printed = cli_output("decode", str(inputs[name]), "--json").splitlines()
    assert lines(list(read(inputs[name]))) == printed and len(printed) > 10
    raw = cli_output("decode", str(inputs[name]), "--json", "--raw").splitlines()
    assert lines(list(read(str(inputs[name]), other_frames=True))) == raw


def test_read_streams_and_takes_a_format(inputs: dict[str, Path]) -> None:
    first = next(read(inputs[CANDUMP_NAME]))  # the first event without reading the rest
    assert (
        json.dumps(first.to_dict(), default=str)
        == cli_output("decode", str(inputs[CANDUMP_NAME]), "--json").splitlines()[0]
    )
    as_stream = list(read(inputs["flight-candump.log"], format="stream"))  # wrong, but asked
    assert {e.fields["kind"] for e in as_stream} == {"garbage"}


def test_read_errors(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="no such file"):
        read(tmp_path / "missing.log")
    (tmp_path / "notes.txt").write_text("nothing to decode here\n", encoding="utf-8")
    with pytest.raises(ValueError, match="cannot tell the format of"):
        read(tmp_path / "notes.txt")
    with pytest.raises(ValueError, match="unknown format 'xls'; valid: candump"):
        read(SAMPLES / "flight-candump.log", format="xls")


def test_read_errors_name_the_library_s_arguments_not_the_command_line_s_options(
    tmp_path: Path,
) -> None:
    """The README is no capture: the library says format=, the argument it takes."""
    with pytest.raises(ValueError) as raised:
        read(Path(__file__).resolve().parent.parent / "README.md")
    assert "give format= (candump, " in str(raised.value)
    assert "--format" not in str(raised.value)
    binary = tmp_path / "flight.log"
    binary.write_bytes(b"(1.0) can0 0F01#\0\0\n")
    with pytest.raises(ValueError, match=r"\(it holds binary data\); give format=$"):
        read(binary)


CASES = [(name, {}) for name in NAMES] + [
    ("flight-candump.log", {"tolerance_deg": 2.0, "time_allowed_s": 3.0, "flag_allowed_s": 0.4}),
]
OPTIONS = {"tolerance_deg": "--tolerance", "time_allowed_s": "--time-allowed",
           "flag_allowed_s": "--flag-allowed"}  # fmt: skip


@pytest.mark.parametrize(("name", "options"), CASES)
def test_analyze_gives_the_findings_analyze_json_prints(
    inputs: dict[str, Path], name: str, options: dict[str, float]
) -> None:
    flags = [text for key, value in options.items() for text in (OPTIONS[key], str(value))]
    printed = cli_output("analyze", str(inputs[name]), "--json", *flags).splitlines()
    findings = list(analyze(inputs[name], **options))
    assert lines(findings) == printed
    assert all(
        f.topic == "/analysis/response" and f.verdict == f.fields["verdict"] for f in findings
    )
    # the events of read(), analysed: the same findings
    assert lines(list(analyze(read(inputs[name]), **options))) == printed
    clockless = name in ("uart-dump.bin", STREAM_NAME)  # raw byte dumps: no findings at all
    assert (len(printed) == 0) if clockless else (len(printed) > 3)


def test_analyze_refuses_options_that_are_not_above_zero() -> None:
    with pytest.raises(ValueError, match="tolerance must be more than 0"):
        analyze(SAMPLES / "flight-candump.log", tolerance_deg=0)
    with pytest.raises(ValueError, match="time allowed must be more than 0"):
        analyze([], time_allowed_s=float("nan"))
    assert list(analyze([])) == []


@pytest.mark.parametrize("name", ["flight-candump.mcap", "faults-candump.mcap"])
def test_recording_events_are_decode_stored(inputs: dict[str, Path], name: str) -> None:
    path = inputs[name]
    printed = cli_output("decode", str(path), "--stored", "--json").splitlines()
    recording = Recording(path)
    assert lines(list(recording.events())) == printed
    assert recording.topics() == sorted({json.loads(line)["topic"] for line in printed})
    assert not recording.recovered
    for topic in recording.topics():
        assert lines(list(recording.events(topic))) == [
            line for line in printed if json.loads(line)["topic"] == topic
        ]
    two = ["/gimbal/command", "/uav/text"]
    assert lines(list(recording.events(two))) == [
        line for line in printed if json.loads(line)["topic"] in two
    ]


def finding_key(row: dict[str, object]) -> str:
    return json.dumps(row, default=str, sort_keys=True)


@pytest.mark.parametrize("name", ["flight-candump.mcap", "faults-candump.mcap"])
def test_recording_table_is_the_table_commands_table(
    inputs: dict[str, Path], name: str, tmp_path: Path
) -> None:
    dataset = tmp_path / "fleet"
    cli_output("table", str(inputs[name]), "-o", str(dataset), "--workers", "1", "-q")
    recording = Recording(inputs[name])
    for topic, table in TOPIC_TABLES.items():
        got, want = recording.table(topic).to_pylist(), rows(dataset, table)
        if topic == "/analysis/response":  # recorded in time order; `table` writes as made
            got, want = sorted(got, key=finding_key), sorted(want, key=finding_key)
        assert got == want, topic
        if topic in recording.topics():
            assert got, topic
    commands = recording.table("/gimbal/command")
    assert commands.schema.field("name").type == pa.string()  # a labelled value: its label
    assert commands.schema.field("s_id").type == pa.int64()
    assert commands.schema.field("time").type == pa.timestamp("us", tz="UTC")
    attitude = recording.table("/gimbal/attitude")
    assert attitude.schema.field("control_mode").type == pa.string()
    assert attitude.schema.field("control_mode_code").type == pa.int64()
    assert attitude.schema.field("pitch_deg").type == pa.float64()


def test_recording_errors(tmp_path: Path, inputs: dict[str, Path]) -> None:
    with pytest.raises(FileNotFoundError):
        Recording(tmp_path / "missing.mcap")
    with pytest.raises(ValueError, match="not an MCAP file"):
        Recording(SAMPLES / "flight-candump.log")
    with pytest.raises(ValueError, match=r"no table for topic '/gimbal'; valid: /gimbal/command"):
        Recording(inputs["flight-candump.mcap"]).table("/gimbal")


@pytest.mark.slow
def test_analyze_judges_a_recordings_camera_alike_from_its_path_and_from_read(
    tmp_path: Path,
) -> None:
    """A recording with video: ``analyze(read(path))`` judges the camera commands from the
    file's pictures as ``analyze(path)`` does, and as ``analyze --json`` prints them; events
    that came without their video say so in the result."""
    from analyzer.sim.ground import Step
    from tests.camera_flights import record

    steps = (
        Step(0.3, "zoom", {"action": "zoom_in_2x"}),
        Step(3.0, "zoom", {"action": "zoom_out_2x"}),
    )
    path = record(tmp_path / "zoom.mcap", steps, 5.0)
    from_path = analyze(path)
    from_read = analyze(read(path))
    assert from_path.camera_judged and from_read.camera_judged
    assert from_path.camera_note == from_read.camera_note == ""
    findings = list(from_path)
    camera = [f for f in findings if f.command.startswith("zoom")]
    assert len(camera) == 2, lines(findings)
    assert (
        lines(list(from_read))
        == lines(findings)
        == cli_output("analyze", "--json", str(path)).splitlines()
    )
    without = analyze(list(read(path)))
    assert not without.camera_judged
    assert without.camera_note == "camera commands not judged: the events came without their video"
    assert lines(list(without)) == lines([f for f in findings if f not in camera])
