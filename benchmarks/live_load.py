"""Live load benchmark: a saturated 1 Mbit/s virtual CAN bus recorded by the capture engine.

A sender thread drives python-can's virtual bus at about 7,600 extended 8-byte frames per
second (the most a 1 Mbit/s bus carries without stuffing): gimbal traffic (commands,
feedback in four segments, UAV GPS / altitude / attitude, text messages) mixed with
foreign IDs. A Capture with an McapSink (or a counting sink with ``--sink count``) records
it. Reported: frames sent vs captured vs written, the recorder's CPU use (CPU time of the
CAN source's reader, capture and MCAP flush threads, measured per thread) and ratios
against the targets of issue 4 (none lost, under 25% of one core).

With an MCAP sink the same load is then recorded a second time while serving it live to
one Foxglove WebSocket client (``--foxglove``, issue 25): a client in a process of its own
(``benchmarks/live_client.py``) subscribes to every channel. The extra CPU of the recorder
(capture and flush threads plus the SDK's server threads) is compared with the recording
alone of the same run (target: a few percent of one core); ``--no-live`` skips it.

The virtual bus only connects buses in one process, so sender and recorder share the
interpreter; the sender's own CPU time is measured separately and not counted.

``convert`` throughput is measured by ``benchmarks/convert_speed.py``; this script runs it
at the end with as many frames as were sent (skip with ``--no-convert``).

    python benchmarks/live_load.py --seconds 30
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

RATE_FPS = 7600  # 1e6 / 131 bits per extended 8-byte frame, rounded down
TARGET_CPU_PCT = 25.0
TARGET_LIVE_EXTRA_PCT = 5.0  # "a few percent of one core" more with one live client
SDK_THREADS = "tokio"  # the foxglove-sdk server's threads (Rust): /proc/self/task/*/comm


class Sender:
    """Sends a paced mix of gimbal and foreign frames on a virtual channel."""

    def __init__(self, channel: str, rate: int, seconds: float) -> None:
        import can

        self.bus = can.Bus(interface="virtual", channel=channel)
        self.rate = rate
        self.seconds = seconds
        self.sent = 0
        self.gimbal_sent = 0
        self.cpu_s = 0.0
        self.late_s = 0.0
        self._messages = self._plan()
        self.thread = threading.Thread(target=self._run, name="sender", daemon=True)

    def _plan(self) -> list[Any]:
        """Every frame of the run, values changing as on a real bus: the traffic of
        ``benchmarks/convert_speed.py`` (a pilot's stick, a moving gimbal, an aircraft on an
        orbit, foreign IDs with counters and sensor bytes), none of it repeated."""
        import can

        from analyzer.protocol.ids import PROTOCOL_IDS
        from analyzer.protocol.uav import encode_text
        from benchmarks.convert_speed import make_frames

        frames = make_frames(int(self.seconds * self.rate) + 1)
        self._text = [
            can.Message(arbitration_id=i, data=d, is_extended_id=True)
            for i, d in encode_text("RTL: low battery")
        ]
        return [
            (
                can.Message(arbitration_id=f.can_id, data=f.data, is_extended_id=f.extended),
                f.can_id in PROTOCOL_IDS,
            )
            for f in frames
        ]

    def _run(self) -> None:
        cpu0 = time.thread_time()
        plan = self._messages
        planned = 0  # frames of the plan sent (text messages come on top)
        start = time.monotonic()
        total = int(self.seconds * self.rate)
        next_text = 5.0
        while self.sent < total:
            elapsed = time.monotonic() - start
            due = min(total, int(elapsed * self.rate) + 1)
            if due - self.sent > self.rate // 10:
                self.late_s = max(self.late_s, (due - self.sent) / self.rate)
            while self.sent < due:
                msg, gimbal = plan[planned]
                planned += 1
                self.bus.send(msg)
                self.sent += 1
                self.gimbal_sent += gimbal
            if elapsed >= next_text:  # a UAV text message every 5 s (on top of the rate)
                next_text += 5.0
                for msg in self._text:
                    self.bus.send(msg)
                    self.sent += 1
                    self.gimbal_sent += 1
                total += len(self._text)
            time.sleep(0.002)
        self.cpu_s = time.thread_time() - cpu0


class CountingSink:
    """Counts what it is handed; stands in when no MCAP writer is wanted."""

    def __init__(self) -> None:
        self.items_written = 0
        self.events_written = 0
        self.error: str | None = None

    def handle(self, batch: Any) -> None:
        self.items_written += len(batch.items)
        self.events_written += len(batch.events)

    def close(self) -> None:
        pass


def thread_cpu(thread: threading.Thread | None) -> float:
    """CPU seconds a live thread has used (Linux/Unix), 0 when unknown."""
    if thread is None or thread.ident is None or not hasattr(time, "pthread_getcpuclockid"):
        return 0.0
    try:
        return time.clock_gettime(time.pthread_getcpuclockid(thread.ident))
    except (OSError, ProcessLookupError):
        return 0.0


def native_threads_cpu(prefix: str) -> dict[int, float]:
    """CPU seconds of this process's threads whose name starts with ``prefix`` (Linux)."""
    out: dict[int, float] = {}
    tick = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    try:
        tasks = os.listdir("/proc/self/task")
    except OSError:
        return out
    for tid in tasks:
        try:
            with open(f"/proc/self/task/{tid}/stat", encoding="utf-8") as stat:
                fields = stat.read()
        except OSError:
            continue
        name = fields[fields.index("(") + 1 : fields.rindex(")")]
        if name.startswith(prefix):
            rest = fields[fields.rindex(")") + 2 :].split()
            out[int(tid)] = (int(rest[11]) + int(rest[12])) / tick  # utime + stime
    return out


class CpuMeter:
    """Samples the CPU time of named threads while they run (their clocks vanish on exit),
    and of the SDK's native server threads (``native`` holds them by thread id)."""

    def __init__(self, names: tuple[str, ...]) -> None:
        self.names = names
        self.last: dict[int, float] = {}
        self.native: dict[int, float] = {}
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._run, name="cpu-meter", daemon=True)

    def sample(self) -> None:
        for thread in threading.enumerate():
            if thread.name in self.names and thread.ident is not None:
                self.last[thread.ident] = max(self.last.get(thread.ident, 0.0), thread_cpu(thread))
        for tid, cpu in native_threads_cpu(SDK_THREADS).items():
            self.native[tid] = max(self.native.get(tid, 0.0), cpu)

    def _run(self) -> None:
        while not self._stop.wait(0.05):
            self.sample()

    def total(self) -> float:
        return sum(self.last.values()) + sum(self.native.values())

    def sdk(self) -> float:
        return sum(self.native.values())

    def stop(self) -> None:
        self._stop.set()
        self.thread.join()


def run(
    seconds: float, rate: int, sink_kind: str, out_dir: str, live: bool = False
) -> dict[str, Any]:
    from analyzer.capture import Capture
    from analyzer.sources import open_source

    channel = f"live-load-{uuid.uuid4().hex[:8]}"
    source = open_source(f"can:virtual:{channel}")
    path = os.path.join(out_dir, "live_load.mcap")
    sink: Any
    if sink_kind == "mcap":
        try:
            from analyzer.mcapio.write.sink import McapSink, recording_metadata
        except ImportError:
            sink_kind = "count"
        else:
            server = client = None
            if live:
                from live_client import LiveClient

                from analyzer.live.options import ListenAddress
                from analyzer.live.server import FoxgloveLive

                server = FoxgloveLive(ListenAddress("127.0.0.1", 0))
                client = LiveClient(server.url)
            meta = recording_metadata(source.description, command="bench")
            sink = McapSink(path, metadata=meta, tee=server)
    if sink_kind == "count":
        sink = CountingSink()
        server = client = None
    capture = Capture(source, [sink] if server is None else [sink, server])
    sender = Sender(channel, rate, seconds)
    meter = CpuMeter(("capture", "mcap-flush", "can"))  # "can": the source's reader thread
    capture.start()
    meter.thread.start()
    wall0 = time.monotonic()
    sender.thread.start()
    sender.thread.join()
    send_wall = time.monotonic() - wall0
    deadline = time.monotonic() + 10.0
    while capture.stats.frames < sender.sent and time.monotonic() < deadline:
        time.sleep(0.05)
    drain_s = time.monotonic() - wall0 - send_wall
    meter.sample()
    capture.stop()
    capture.join(30.0)
    meter.stop()
    wall = time.monotonic() - wall0
    sender.bus.shutdown()
    stats = capture.stats
    size = os.path.getsize(path) if sink_kind == "mcap" and os.path.exists(path) else 0
    served = server.status() if server is not None else None
    client_got = client.received() if client is not None else (0, 0)
    return {
        "sink": sink_kind + (" + foxglove client" if live else ""),
        "live_sent": served.messages if served is not None else 0,
        "live_drop_reports": served.drop_reports if served is not None else 0,
        "client_received": client_got[0],
        "client_bytes": client_got[1],
        "sdk_cpu_s": meter.sdk(),
        "seconds": seconds,
        "wall_s": wall,
        "send_wall_s": send_wall,
        "drain_s": drain_s,
        "sent": sender.sent,
        "gimbal_sent": sender.gimbal_sent,
        "captured": stats.frames,
        "written": getattr(sink, "items_written", 0),
        "events": stats.events,
        "diagnostics": stats.diagnostics,
        "diagnostic_kinds": stats.diagnostic_kinds,
        "sender_cpu_s": sender.cpu_s,
        "sender_late_s": sender.late_s,
        "recorder_cpu_s": meter.total(),
        "mcap_bytes": size,
        "error": str(capture.error) if capture.error else "",
        "max_bus_load_pct": stats.bus_load_pct,
    }


def report(result: dict[str, Any]) -> list[str]:
    sent, captured, written = result["sent"], result["captured"], result["written"]
    cpu_pct = 100.0 * result["recorder_cpu_s"] / result["send_wall_s"]
    lines = [
        f"sink: {result['sink']}   duration: {result['seconds']:g} s "
        f"(sending took {result['send_wall_s']:.1f} s, drain {result['drain_s']:.2f} s)",
        f"frames sent:      {sent:>9}  ({sent / result['send_wall_s']:.0f}/s, "
        f"{result['gimbal_sent']} gimbal protocol frames)",
        f"frames captured:  {captured:>9}  ratio {captured / sent:.6f}  lost {sent - captured}",
        f"frames written:   {written:>9}  ratio {written / sent:.6f}",
        f"events decoded:   {result['events']:>9}  diagnostics {result['diagnostics']} "
        f"{result['diagnostic_kinds']}",
        f"recorder CPU:     {result['recorder_cpu_s']:.2f} s = {cpu_pct:.1f}% of one core "
        f"(target < {TARGET_CPU_PCT:.0f}%: ratio {cpu_pct / TARGET_CPU_PCT:.2f})",
        f"sender CPU:       {result['sender_cpu_s']:.2f} s (not counted; same process)",
    ]
    if result["mcap_bytes"]:
        lines.append(f"recording size:   {result['mcap_bytes'] / 1e6:.1f} MB")
    if result["live_sent"]:
        lines.append(
            f"served live:      {result['live_sent']} messages, the client received "
            f"{result['client_received']} ({result['client_bytes'] / 1e6:.1f} MB); SDK "
            f"threads {result['sdk_cpu_s']:.2f} s CPU; drop reports {result['live_drop_reports']}"
        )
    if result["sender_late_s"] > 0.1:
        lines.append(f"note: the sender fell behind by up to {result['sender_late_s']:.2f} s")
    if result["error"]:
        lines.append(f"capture error:    {result['error']}")
    verdict = "PASS" if captured == sent == written and cpu_pct < TARGET_CPU_PCT else "FAIL"
    lines.append(f"verdict: {verdict} (none lost, CPU under {TARGET_CPU_PCT:.0f}% of one core)")
    return lines


def live_report(alone: dict[str, Any], served: dict[str, Any]) -> list[str]:
    """Recording alone vs recording while serving one live client, same run."""
    pct = [100.0 * r["recorder_cpu_s"] / r["send_wall_s"] for r in (alone, served)]
    extra = pct[1] - pct[0]
    ok = extra < TARGET_LIVE_EXTRA_PCT and served["captured"] == served["sent"]
    return [
        "== recording alone vs recording + one Foxglove client (same run)",
        f"recorder CPU:     {pct[0]:.1f}% alone, {pct[1]:.1f}% with the client "
        f"(ratio {pct[1] / pct[0]:.2f}); extra {extra:.1f}% of one core "
        f"(target < {TARGET_LIVE_EXTRA_PCT:.0f}%: ratio {extra / TARGET_LIVE_EXTRA_PCT:.2f})",
        f"client got:       {served['client_received']} of {served['live_sent']} messages "
        f"served ({served['client_received'] / max(1, served['live_sent']):.4f})",
        f"verdict: {'PASS' if ok else 'FAIL'} (none lost, extra CPU under "
        f"{TARGET_LIVE_EXTRA_PCT:.0f}% of one core)",
    ]


def convert_report(frames: int) -> list[str]:
    """Run the ``convert`` throughput benchmark (benchmarks/convert_speed.py) for ``frames``."""
    path = Path(__file__).with_name("convert_speed.py")
    if not path.exists():
        return ["convert throughput: not measured (benchmarks/convert_speed.py is missing)"]
    command = [sys.executable, str(path), "--frames", str(frames), "--repeat", "1"]
    done = subprocess.run(command, capture_output=True, text=True, check=False, encoding="utf-8")
    lines = ["== convert throughput (benchmarks/convert_speed.py)"]
    lines += (done.stdout + done.stderr).rstrip().splitlines()
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=30.0, help="how long to send (default 30)")
    parser.add_argument(
        "--rate", type=int, default=RATE_FPS, help="frames per second (default 7600)"
    )
    parser.add_argument(
        "--sink", choices=("mcap", "count"), default="mcap", help="what records (default mcap)"
    )
    parser.add_argument("--keep", metavar="DIR", help="keep the recording in DIR")
    parser.add_argument("--no-convert", action="store_true", help="skip the convert hook")
    parser.add_argument(
        "--no-live", action="store_true", help="skip the run with a live Foxglove client"
    )
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        out_dir = args.keep or tmp
        result = run(args.seconds, args.rate, args.sink, out_dir)
        for line in report(result):
            print(line)
        if args.sink == "mcap" and not args.no_live:
            print("== the same, recorded while serving one Foxglove WebSocket client")
            served = run(args.seconds, args.rate, args.sink, out_dir, live=True)
            for line in report(served) + live_report(result, served):
                print(line)
        if not args.no_convert:
            for line in convert_report(result["sent"]):
                print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
