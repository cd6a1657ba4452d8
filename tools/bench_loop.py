"""The loop's own overhead per step with no stages, and the real clock's lateness at the deadline."""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from engine.clock import RealClock, VirtualClock
from engine.loop import FixedStepLoop


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--steps", type=int, default=20000, help="steps for the overhead figure")
    p.add_argument("--frames", type=int, default=120, help="real-time frames for the lateness figure")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def loop_overhead_us(steps: int) -> float:
    """Mean wall time per step of a loop with no stages on a virtual clock (pure bookkeeping)."""
    loop = FixedStepLoop(clock=VirtualClock())
    t0 = time.perf_counter_ns()
    loop.run(steps=steps)
    return (time.perf_counter_ns() - t0) / steps / 1000


def bare_loop_us(steps: int) -> float:
    """The peer: a bare Python for-loop calling an empty function per step."""
    def nothing(step: int, dt: float) -> None:
        pass
    t0 = time.perf_counter_ns()
    for i in range(steps):
        nothing(i, 1 / 60)
    return (time.perf_counter_ns() - t0) / steps / 1000


def deadline_lateness_us(frames: int) -> np.ndarray:
    """How late the real clock's wait_until returns, per frame, in µs."""
    clock = RealClock()
    late = np.empty(frames)
    deadline = clock.now_ns()
    for i in range(frames):
        deadline += 16_666_667
        clock.wait_until(deadline)
        late[i] = (clock.now_ns() - deadline) / 1000
    return late


def run(args: argparse.Namespace) -> int:
    overhead = loop_overhead_us(args.steps)
    bare = bare_loop_us(args.steps)
    late = deadline_lateness_us(args.frames)
    sleep_late = []
    for _ in range(min(args.frames, 60)):  # peer: plain time.sleep to the deadline
        t0 = time.perf_counter_ns()
        time.sleep(1 / 60)
        sleep_late.append((time.perf_counter_ns() - t0) / 1000 - 16666.667)
    fig = {
        "loop_overhead_us_per_step": overhead,
        "bare_call_us_per_step": bare,
        "overhead_ratio_vs_bare_call": overhead / bare if bare else None,
        "deadline_lateness_us": {"median": float(np.median(late)), "p99": float(np.percentile(late, 99)), "max": float(late.max())},
        "plain_sleep_lateness_us": {"median": float(np.median(sleep_late)), "p99": float(np.percentile(sleep_late, 99))},
    }
    if args.json:
        print(json.dumps(fig, indent=2))
        return 0
    print(f"loop overhead per step (no stages, virtual clock): {overhead:8.2f} us")
    print(f"peer: bare Python call per step:                   {bare:8.2f} us  (ratio {fig['overhead_ratio_vs_bare_call']:.1f}x)")
    d = fig["deadline_lateness_us"]
    s = fig["plain_sleep_lateness_us"]
    print(f"real clock lateness at the deadline (sleep+spin):  median {d['median']:.1f} us, p99 {d['p99']:.1f} us, max {d['max']:.1f} us")
    print(f"peer: plain time.sleep(1/60) lateness:             median {s['median']:.1f} us, p99 {s['p99']:.1f} us")
    return 0
