"""SocketCAN interfaces as /sys/class/net shows them: which exist, which are up."""

from __future__ import annotations

import contextlib
from pathlib import Path

from analyzer.sources.spec import DEFAULT_CAN_BITRATE

SYS_NET = Path("/sys/class/net")
ARPHRD_CAN = 280  # /sys/class/net/IF/type of a CAN interface
IFF_UP = 0x1


def bring_up(name: str) -> str:
    """The command that brings a SocketCAN interface up at the gimbal's bitrate, listening."""
    return f"sudo ip link set {name} up type can bitrate {DEFAULT_CAN_BITRATE} listen-only on"


def socketcan_links(sys_net: Path = SYS_NET) -> dict[str, str]:
    """Every SocketCAN interface, up or down: name -> "up" / "down" (python-can lists only
    the ones that are up, and a down can0 is the first thing to tell a user about)."""
    links: dict[str, str] = {}
    with contextlib.suppress(OSError):
        for entry in sorted(sys_net.iterdir()):
            try:
                if int((entry / "type").read_text(encoding="utf-8").strip()) != ARPHRD_CAN:
                    continue
                flags = int((entry / "flags").read_text(encoding="utf-8").strip(), 16)
            except (OSError, ValueError):
                continue
            links[entry.name] = "up" if flags & IFF_UP else "down"
    return links


def socketcan_down(name: str, sys_net: Path = SYS_NET) -> bool:
    """True when ``name`` is a SocketCAN interface that is down (bound, it receives nothing)."""
    try:
        flags = int((sys_net / name / "flags").read_text(encoding="utf-8").strip(), 16)
    except (OSError, ValueError):
        return False  # not a network interface here: python-can says what is wrong
    return not flags & IFF_UP
