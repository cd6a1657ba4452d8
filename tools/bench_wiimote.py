"""The Wiimote driver's cost per 60 Hz poll, against the emulator alone as the peer.

A session of the real driver on the emulated remote runs on a virtual clock (no waiting);
each poll's wall time is measured. The peer is the emulator producing and handing over the
same reports with no driver on top, so `driver - emulator` is what the driver adds to a
frame, shown also as a share of the 16.7 ms frame budget. decode_report alone is timed too.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from engine import arguments
from engine.clock import VirtualClock
from engine.recording import Recording

STEP_NS = 16_666_667


def add_arguments(p: argparse.ArgumentParser) -> None:
    # at most an hour, as bench serial's: 1e12 s was a numpy memory error (a traceback)
    p.add_argument("--seconds", type=arguments.float_range(0.0, 3600.0, lo_open=True), default=20.0,
                   help="virtual seconds per session (default 20; at most 3600)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def _recording() -> Recording:
    t = np.arange(0, 10, 1 / 60)
    a = np.empty((len(t), 2, 3))
    a[:, :, 0] = np.sin(3 * t)[:, None]
    a[:, :, 1] = 0.2
    a[:, :, 2] = 1.0 - 0.5 * np.cos(2 * t)[:, None]
    return Recording(t, a)


def driver_poll_us(seconds: float) -> tuple[np.ndarray, int]:
    from engine.sensors.wiimote import WiimoteSource
    from engine.sensors.wiimote.emulator import EmulatedBus, EmulatedWiimote

    vc = VirtualClock()
    src = WiimoteSource(clock=vc.seconds, backend=EmulatedBus([EmulatedWiimote(_recording(), vc.seconds)]))
    steps = int(seconds * 60)
    times = np.empty(steps)
    n = 0
    for i in range(steps):
        vc.advance(STEP_NS)
        t0 = time.perf_counter_ns()
        n += len(src.poll())
        times[i] = (time.perf_counter_ns() - t0) / 1000
    return times[30:], n  # after the set-up


def emulator_only_us(seconds: float) -> np.ndarray:
    from engine.sensors.wiimote.emulator import EmulatedWiimote

    vc = VirtualClock()
    emu = EmulatedWiimote(_recording(), vc.seconds)
    emu.handle_output(bytes([0x12, 0x04, 0x35]))
    steps = int(seconds * 60)
    times = np.empty(steps)
    for i in range(steps):
        vc.advance(STEP_NS)
        t0 = time.perf_counter_ns()
        while emu.take(vc.seconds()) is not None:
            pass
        times[i] = (time.perf_counter_ns() - t0) / 1000
    return times[30:]


def decode_us(reps: int = 20000) -> float:
    from engine.sensors.wiimote import decode_report

    report = bytes([0x35, 0x60, 0x20, 0x80, 0x81, 0x9A]) + bytes(range(16))
    t0 = time.perf_counter_ns()
    for _ in range(reps):
        decode_report(report)
    return (time.perf_counter_ns() - t0) / reps / 1000


def run(args: argparse.Namespace) -> int:
    drv, samples = driver_poll_us(args.seconds)
    emu = emulator_only_us(args.seconds)
    added = float(np.median(drv) - np.median(emu))
    fig = {
        "samples_per_s": samples / args.seconds,
        "poll_median_us": float(np.median(drv)),
        "poll_p99_us": float(np.percentile(drv, 99)),
        "emulator_median_us": float(np.median(emu)),
        "driver_added_median_us": added,
        "driver_share_of_16.7ms_budget_pct": 100 * added / 16666.7,
        "decode_report_us": decode_us(),
        "poll_vs_emulator_ratio": float(np.median(drv) / max(np.median(emu), 1e-9)),
    }
    if args.json:
        print(json.dumps(fig, indent=2))
    else:
        for k, v in fig.items():
            print(f"{k:>36}: {v:10.2f}")
    return 0
