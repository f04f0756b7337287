"""`interfaces` names the CAN adapters and serial ports here, each with a --source that works."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import types
from pathlib import Path
from typing import Any

import pytest
from can.interfaces import BACKENDS
from serial.tools.list_ports_common import ListPortInfo

from analyzer.cli import main
from analyzer.sources import detect
from analyzer.sources.can_bus import bus_arguments
from analyzer.sources.spec import CanSpec, SerialSpec, parse_source
from tests.platforms import symlinks

ROOT = Path(__file__).resolve().parent.parent
CANABLE_BY_ID = "/dev/serial/by-id/usb-canable.io_CANable_8c005eb_0037001A5948-if00"
FTDI_BY_ID = "/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A10KZP4M-if00"


def usb_port(device: str, vid: int, pid: int, serial: str, product: str, maker: str) -> Any:
    """A port as pyserial's Linux lister fills it in for a USB device."""
    port = ListPortInfo(device, skip_link_detection=True)
    port.vid, port.pid, port.serial_number = vid, pid, serial
    port.product, port.manufacturer = product, maker
    port.description = port.usb_description()
    port.hwid = port.usb_info()
    return port


@pytest.fixture
def field_laptop(monkeypatch: pytest.MonkeyPatch) -> None:
    """A laptop with a PCAN-USB, a gs_usb adapter as can0 (up), can1 (down), a CANable
    with slcan firmware, an FTDI cable on the gimbal's UART and a built-in ttyS0."""
    configs = [
        {"interface": "socketcan", "channel": "can0"},
        {"interface": "pcan", "channel": "PCAN_USBBUS1", "supports_fd": True},
        {"interface": "virtual", "channel": "channel-4352"},
        {"interface": "udp_multicast", "channel": "239.74.163.2"},
        {"interface": "serial", "channel": "/dev/ttyACM0"},
    ]
    ports = [
        ListPortInfo("/dev/ttyS0", skip_link_detection=True),
        usb_port("/dev/ttyUSB0", 0x0403, 0x6001, "A10KZP4M", "FT232R USB UART", "FTDI"),
        usb_port("/dev/ttyACM0", 0x16D0, 0x117E, "0037001A5948", "CANable 8c005eb", "canable.io"),
    ]
    stable = {"/dev/ttyACM0": CANABLE_BY_ID, "/dev/ttyUSB0": FTDI_BY_ID}
    monkeypatch.setattr(detect, "python_can_configs", lambda problems: configs)
    monkeypatch.setattr(detect, "socketcan_links", lambda: {"can0": "up", "can1": "down"})
    monkeypatch.setattr(detect, "pyserial_ports", lambda: ports)
    monkeypatch.setattr(detect, "by_id_links", lambda: stable)


def test_each_adapter_with_its_source_line(
    field_laptop: None, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["interfaces"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("CAN adapters (python-can):\n  socketcan can0 (up)\n")
    assert "      --source can:socketcan:can0\n" in out
    assert "sudo ip link set can0 type can bitrate 1000000 listen-only on" in out
    assert "  socketcan can1 (down)\n" in out
    assert (
        "the link is down: sudo ip link set can1 up type can bitrate 1000000 listen-only on"
    ) in out
    assert "  pcan PCAN_USBBUS1\n      --source can:pcan:PCAN_USBBUS1@1000000\n" in out
    assert "listen-only: requested from the adapter" in out
    assert "virtual" not in out and "udp_multicast" not in out  # no adapters
    serial = out[out.index("Serial ports (pyserial):") :]
    # USB ports first, each with vendor:product, serial number and its by-id name
    assert serial.index("/dev/ttyACM0") < serial.index("/dev/ttyUSB0") < serial.index("ttyS0")
    assert "  /dev/ttyACM0  CANable 8c005eb  USB 16d0:117e  serial 0037001A5948" in out
    assert (
        "CANable / CANtact with slcan firmware: "
        f"--source can:slcan:{CANABLE_BY_ID}@1000000  (listen-only)"
    ) in out
    assert f"the gimbal's UART: --source serial:{FTDI_BY_ID}@115200" in out
    assert f"if it is an slcan CAN adapter: --source can:slcan:{FTDI_BY_ID}@1000000" in out
    assert "  /dev/ttyS0\n      the gimbal's UART: --source serial:/dev/ttyS0@115200\n" in out
    assert "@1000000 is the gimbal's CAN bitrate" in out


def test_json_lists_the_same(field_laptop: None, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["interfaces", "--json"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert [(a["interface"], a["channel"], a["state"]) for a in found["can"]] == [
        ("socketcan", "can0", "up"),
        ("pcan", "PCAN_USBBUS1", None),
        ("socketcan", "can1", "down"),
    ]
    assert found["can"][1]["config"]["supports_fd"] is True
    canable = found["serial"][0]
    assert canable == {
        "device": "/dev/ttyACM0",
        "stable_path": CANABLE_BY_ID,
        "description": "CANable 8c005eb",
        "usb": "16d0:117e",
        "vid": 0x16D0,
        "pid": 0x117E,
        "serial_number": "0037001A5948",
        "manufacturer": "canable.io",
        "product": "CANable 8c005eb",
        "slcan_adapter": "CANable / CANtact with slcan firmware",
        "source": f"can:slcan:{CANABLE_BY_ID}@1000000",
        "serial_source": f"serial:{CANABLE_BY_ID}@115200",
        "slcan_source": f"can:slcan:{CANABLE_BY_ID}@1000000",
    }
    # every line given is one --source takes, with the gimbal's bitrate
    for adapter in found["can"]:
        spec = parse_source(adapter["source"])
        assert isinstance(spec, CanSpec) and spec.channel == adapter["channel"]
        assert spec.bitrate == (None if adapter["interface"] == "socketcan" else 1_000_000)
    for port in found["serial"]:
        assert isinstance(parse_source(port["serial_source"]), SerialSpec)
        assert parse_source(port["slcan_source"]) == CanSpec(
            "slcan", port["stable_path"] or port["device"], 1_000_000
        )


def test_a_backend_whose_detection_fails_is_named_and_the_rest_listed(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import can

    def detect_available_configs(interfaces: Any, timeout: float = 5.0) -> list[Any]:
        if interfaces == "kvaser" or "kvaser" in interfaces:
            raise can.CanInterfaceNotImplementedError("canlib: driver crashed")
        if interfaces == "pcan":
            return [{"interface": "pcan", "channel": "PCAN_USBBUS1"}]
        return []

    monkeypatch.setattr(can, "detect_available_configs", detect_available_configs)
    monkeypatch.setattr(detect, "socketcan_links", lambda: {})
    monkeypatch.setattr(detect, "pyserial_ports", lambda: [])
    assert main(["interfaces"]) == 0
    out = capsys.readouterr().out
    assert "  pcan PCAN_USBBUS1\n      --source can:pcan:PCAN_USBBUS1@1000000\n" in out
    assert (
        "Not searched completely:\n  python-can kvaser: detection failed: canlib: driver crashed\n"
        in out
    )
    assert "Serial ports (pyserial):\n  none found\n" in out


def test_socketcan_links_up_and_down_from_sysfs(tmp_path: Path) -> None:
    def interface(name: str, kind: int, flags: str) -> None:
        (tmp_path / name).mkdir()
        (tmp_path / name / "type").write_text(f"{kind}\n", encoding="utf-8")
        (tmp_path / name / "flags").write_text(f"{flags}\n", encoding="utf-8")

    interface("can0", 280, "0x40081")  # UP, RUNNING, NOARP: as a gs_usb can0 that is up
    interface("can1", 280, "0x80")  # NOARP only: down
    interface("eth0", 1, "0x1003")
    interface("lo", 772, "0x9")
    assert detect.socketcan_links(tmp_path) == {"can0": "up", "can1": "down"}
    assert detect.socketcan_links(tmp_path / "missing") == {}


@symlinks
def test_stable_names_from_by_id_links(tmp_path: Path) -> None:
    device = tmp_path / "ttyACM3"
    device.touch()
    by_id = tmp_path / "by-id"
    by_id.mkdir()
    (by_id / "usb-canable.io_CANable_8c005eb_0037001A5948-if00").symlink_to(device)
    stable = detect.by_id_links(str(by_id))
    assert stable == {str(device): str(by_id / "usb-canable.io_CANable_8c005eb_0037001A5948-if00")}
    ports = detect.serial_ports([ListPortInfo(str(device), skip_link_detection=True)], stable)
    assert ports[0].serial_source == f"serial:{by_id}/{os.listdir(by_id)[0]}@115200"


@pytest.mark.slow
def test_a_real_run_lists_what_pyserial_and_python_can_see(tmp_path: Path) -> None:
    from serial.tools import list_ports

    proc = subprocess.run(
        [sys.executable, "-m", "analyzer", "interfaces", "--json"],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=120,
        encoding="utf-8",
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""  # the warnings of python-can's absent backends are not news
    found = json.loads(proc.stdout)
    assert sorted(p["device"] for p in found["serial"]) == sorted(
        p.device for p in list_ports.comports()
    )
    for adapter in found["can"]:
        assert isinstance(parse_source(adapter["source"]), CanSpec)
        assert adapter["interface"] not in ("virtual", "udp_multicast", "serial")
    text = subprocess.run(
        [sys.executable, "-m", "analyzer", "interfaces"],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=120,
        encoding="utf-8",
    )
    assert text.returncode == 0 and text.stdout.startswith("CAN adapters (python-can):\n")
    assert all(f"--source {p['serial_source']}" in text.stdout for p in found["serial"])


def vector_channel(serial: int, hw_channel: int, index: int) -> Any:
    """A channel as the Vector XL driver describes it (python-can's VectorChannelConfig)."""
    from can.interfaces.vector import canlib, xldefine

    return canlib.VectorChannelConfig(
        name=f"VN1630A Channel {hw_channel + 1}",
        hw_type=xldefine.XL_HardwareType.XL_HWTYPE_VN1630,
        hw_index=0,
        hw_channel=hw_channel,
        channel_index=index,
        channel_mask=1 << index,
        channel_capabilities=xldefine.XL_ChannelCapabilities(0),
        channel_bus_capabilities=xldefine.XL_BusCapabilities.XL_BUS_ACTIVE_CAP_CAN,
        is_on_bus=False,
        connected_bus_type=xldefine.XL_BusTypes.XL_BUS_TYPE_CAN,
        bus_params=None,
        serial_number=serial,
        article_number=0,
        transceiver_name="On board CAN 1051cap(Highspeed)",
    )


def test_a_vector_channel_keeps_its_devices_serial_number(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two VN1630A on one laptop: channel 0 of each is told apart by the serial number,
    from python-can's own detection (its XL driver stood in for: Windows only)."""
    from can.interfaces.vector import canlib

    channels = [vector_channel(5050, 0, 0), vector_channel(5050, 1, 1), vector_channel(7070, 0, 2)]
    monkeypatch.setattr(canlib, "get_channel_configs", lambda: channels)
    monkeypatch.setattr(detect, "NOT_SEARCHED", detect.NOT_SEARCHED | (set(BACKENDS) - {"vector"}))
    monkeypatch.setattr(detect, "socketcan_links", lambda: {})
    monkeypatch.setattr(detect, "pyserial_ports", lambda: [])
    assert main(["interfaces", "--json"]) == 0
    sources = [adapter["source"] for adapter in json.loads(capsys.readouterr().out)["can"]]
    assert sources == [
        "can:vector:0@1000000,serial=5050",
        "can:vector:1@1000000,serial=5050",
        "can:vector:0@1000000,serial=7070",
    ]
    spec = parse_source(sources[2])
    assert spec == CanSpec("vector", "0", 1_000_000, (("serial", 7070),))
    kwargs = bus_arguments(spec)  # what can.Bus is given
    assert (kwargs["channel"], kwargs["serial"], kwargs["listen_only"]) == ("0", 7070, True)


def test_options_after_the_channel_and_commas_inside_it() -> None:
    assert parse_source("can:vector:0,serial=12,app_name=CANalyzer") == CanSpec(
        "vector", "0", 1_000_000, (("serial", 12), ("app_name", "CANalyzer"))
    )
    assert parse_source("can:slcan:/dev/odd,name@115200").channel == "/dev/odd,name"
    assert str(parse_source("can:vector:0@500000,serial=12")) == "can:vector:0@500000,serial=12"


class FakeGsUsb:
    """What the gs_usb package's ``GsUsb.scan()`` gives: one per candleLight on USB."""

    def __init__(self, serial: str, bus: int, address: int) -> None:
        self.serial_number, self.bus, self.address = serial, bus, address


def fake_gs_usb(monkeypatch: pytest.MonkeyPatch, devices: list[FakeGsUsb]) -> None:
    package, module = types.ModuleType("gs_usb"), types.ModuleType("gs_usb.gs_usb")
    module.GsUsb = type("GsUsb", (), {"scan": staticmethod(lambda: devices)})  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "gs_usb", package)
    monkeypatch.setitem(sys.modules, "gs_usb.gs_usb", module)


def test_gs_usb_adapters_are_listed_through_pyusb_off_linux(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    fake_gs_usb(monkeypatch, [FakeGsUsb("0037001A5948", 1, 4), FakeGsUsb("00410E3B", 1, 7)])
    problems: list[str] = []
    configs = detect.gs_usb_configs(problems, platform="win32")
    adapters = detect.can_adapters(configs, {})
    assert [a.source for a in adapters] == ["can:gs_usb:0@1000000", "can:gs_usb:1@1000000"]
    assert adapters[1].config["serial"] == "00410E3B" and not problems
    assert bus_arguments(parse_source(adapters[1].source))["index"] == 1  # python-can 4.6
    # Linux: the kernel's gs_usb driver makes them SocketCAN interfaces, listed as such
    assert detect.gs_usb_configs(problems, platform="linux") == []


def test_gs_usb_without_its_package_or_libusb(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "gs_usb", None)  # python-can[gs-usb] not installed
    assert detect.gs_usb_configs([], platform="darwin") == []

    def no_backend() -> list[FakeGsUsb]:
        raise RuntimeError("No backend available")  # pyusb's NoBackendError: no libusb

    fake_gs_usb(monkeypatch, [])
    sys.modules["gs_usb.gs_usb"].GsUsb.scan = staticmethod(no_backend)  # type: ignore[attr-defined]
    problems: list[str] = []
    assert detect.gs_usb_configs(problems, platform="darwin") == []
    assert problems == ["gs_usb: detection failed: No backend available"]
