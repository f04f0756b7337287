"""What to do about a bus's error frames, in the words of someone standing at the gimbal."""

from __future__ import annotations

from analyzer.bus_figures import BusFigures
from analyzer.protocol.bus_state import BUS_OFF
from analyzer.protocol.ids import CAN_BITRATE
from analyzer.timefmt import UTC, TimeZone

# Protocol violations that come from a bitrate or a termination that does not fit the bus.
SIGNAL_ERRORS = (
    "single-bit-error",
    "frame-format-error",
    "bit-stuffing-error",
    "tx-dominant-bit-error",
    "tx-recessive-bit-error",
)
MANY_SIGNAL_ERRORS = 10  # this many stuff / form / bit errors are no passing disturbance
_RATE = f"{CAN_BITRATE // 1_000_000} Mbit/s"


def _frames(count: int) -> str:
    return f"{count:,} error frame" + ("" if count == 1 else "s")


def bus_hints(bus: BusFigures, frames: int, zone: TimeZone = UTC) -> list[str]:
    """Hints from the error frames of a run that read ``frames`` CAN frames in all (for
    people: their times in ``zone``)."""
    if not bus:
        return []
    hints: list[str] = []
    error_frames = bus.error_frames
    no_ack = sum(b.classes["no-acknowledgement-on-tx"] for b in bus.channels.values())
    no_ack += sum(b.locations["acknowledge-slot"] for b in bus.channels.values())
    # Only missing acknowledgements: the adapter's own frames found no listener (below).
    only_errors = frames > 0 and error_frames >= frames and no_ack < error_frames
    if only_errors:
        hints.append(
            f"the adapter received only error frames ({error_frames:,}), no data frame: "
            f"its bitrate is not the bus's; the gimbal's protocol runs at {_RATE} "
            f"(SocketCAN: ip link set can0 type can bitrate {CAN_BITRATE}; other adapters: "
            f"--source can:INTERFACE:CHANNEL@{CAN_BITRATE})"
        )
    if no_ack:
        hints.append(
            f"no acknowledgement ({_frames(no_ack)}): nothing on the bus acknowledges "
            "the frames sent; is the gimbal powered, wired to this bus (CAN-H, CAN-L, "
            f"ground) and at the same bitrate? The gimbal's protocol runs at {_RATE}"
        )
    signal = sum(b.protocol[name] for b in bus.channels.values() for name in SIGNAL_ERRORS)
    if signal >= MANY_SIGNAL_ERRORS and not only_errors:
        hints.append(
            f"{signal:,} stuff / form / bit errors: the bitrate or the termination is wrong; "
            f"check every node runs at {_RATE} and the bus has one 120 ohm resistor at "
            "each end (about 60 ohm between CAN-H and CAN-L, measured with power off)"
        )
    wiring = sorted({state for b in bus.channels.values() for state in b.transceiver})
    wiring = [state for state in wiring if state != "unspecified"]
    if wiring:
        hints.append(f"the transceiver reports {', '.join(wiring)}: check the CAN-H / CAN-L wiring")
    overflow = sum(b.controller["rx-overflow"] for b in bus.channels.values())
    if overflow:
        hints.append(
            f"{overflow:,} receive overflows: the adapter or the computer could not keep up "
            "and frames were lost"
        )
    for name, channel in sorted(bus.channels.items()):
        if channel.worst == BUS_OFF and channel.worst_time is not None:
            back = "and came back" if channel.state != BUS_OFF else "and stayed there"
            hints.append(
                f"{name} went bus-off at {zone.format_datetime(channel.worst_time)} {back}: a "
                "controller in bus-off neither sends nor receives until it is restarted "
                f"(SocketCAN restarts it by itself after: ip link set {name} type can "
                "restart-ms 100)"
            )
    return hints
