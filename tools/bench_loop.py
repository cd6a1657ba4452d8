"""The loop's own overhead per step with no stages, and the real clock's lateness at the deadline.

Overhead: a FixedStepLoop with no stages and no render on a virtual clock (so no waiting),
wall time per step including its budget bookkeeping; the peer is a bare Python call per step
measured in the same run. Lateness: a FixedStepLoop on the real clock for `--frames` frames,
how late each wait returned after its absolute deadline (sleep until a learnt 0.3-2 ms before,
then spin) and the share of a core the idle loop takes; the peers are the fixed 2 ms spin the
clock had before and a plain `time.sleep(1/60)`, measured in the same run.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from engine import arguments
from engine.clock import SPIN_NS, RealClock, VirtualClock
from engine.loop import FixedStepLoop


def add_arguments(p: argparse.ArgumentParser) -> None:
    # 0 was a division by zero (--steps) or an empty percentile (--frames): tracebacks
    p.add_argument("--steps", type=arguments.int_range(1, 10_000_000), default=20000, help="steps for the overhead figure (default 20000)")
    p.add_argument("--frames", type=arguments.int_range(1, 216_000), default=300, help="real-time frames for the lateness figure (default 300, 5 s)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def loop_overhead_us(steps: int, repeats: int = 3) -> float:
    """Best-of-`repeats` mean wall time per step of a loop with no stages on a virtual clock."""
    best = float("inf")
    for _ in range(repeats):
        loop = FixedStepLoop(clock=VirtualClock(), auto_freeze_gc=False)
        loop.run(steps=100)  # warm-up: first-frame path, allocations
        t0 = time.perf_counter_ns()
        loop.run(steps=steps)
        best = min(best, (time.perf_counter_ns() - t0) / steps / 1000)
    return best


def bare_loop_us(steps: int, repeats: int = 3) -> float:
    """The peer: a bare Python for-loop calling an empty function per step."""
    def nothing(step: int, dt: float) -> None:
        pass

    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter_ns()
        for i in range(steps):
            nothing(i, 1 / 60)
        best = min(best, (time.perf_counter_ns() - t0) / steps / 1000)
    return best


class FixedSpinClock(RealClock):
    """The peer of the learnt spin: the real clock as it was, spinning the last SPIN_NS (2 ms)
    before every deadline."""

    def wait_until(self, deadline_ns: int) -> None:
        self.spin_ns = SPIN_NS
        super().wait_until(deadline_ns)


def deadline_lateness_us(frames: int, clock: RealClock | None = None) -> tuple[np.ndarray, float]:
    """How late the real loop's waits return after their deadlines, per frame, in µs, and the
    share of one core the idle loop took (process CPU time over wall time, %)."""
    loop = FixedStepLoop(clock=clock or RealClock(), auto_freeze_gc=False)
    late = np.empty(frames)
    wall0, cpu0 = time.perf_counter_ns(), time.process_time_ns()
    for i in range(frames):
        loop.run_frame()
        late[i] = loop.last_lateness_ns / 1000
    cpu_percent = 100 * (time.process_time_ns() - cpu0) / max(1, time.perf_counter_ns() - wall0)
    return late, cpu_percent


def plain_sleep_lateness_us(frames: int) -> np.ndarray:
    late = np.empty(frames)
    for i in range(frames):
        t0 = time.perf_counter_ns()
        time.sleep(1 / 60)
        late[i] = (time.perf_counter_ns() - t0) / 1000 - 1e6 / 60
    return late


def run(args: argparse.Namespace) -> int:
    overhead = loop_overhead_us(args.steps)
    bare = bare_loop_us(args.steps)
    late, cpu = deadline_lateness_us(args.frames)
    fixed_late, fixed_cpu = deadline_lateness_us(args.frames, FixedSpinClock())
    sleep_late = plain_sleep_lateness_us(min(args.frames, 120))
    fig = {
        "loop_overhead_us_per_step": overhead,
        "bare_call_us_per_step": bare,
        "overhead_ratio_vs_bare_call": overhead / bare if bare else None,
        "deadline_lateness_us": {
            "median": float(np.median(late)), "p99": float(np.percentile(late, 99)),
            "max": float(late.max()), "frames": len(late),
        },
        "idle_loop_cpu_percent": cpu,
        "fixed_2ms_spin": {
            "median_lateness_us": float(np.median(fixed_late)), "p99_lateness_us": float(np.percentile(fixed_late, 99)),
            "idle_loop_cpu_percent": fixed_cpu,
        },
        "idle_cpu_ratio_vs_fixed_spin": cpu / fixed_cpu if fixed_cpu else None,
        "plain_sleep_lateness_us": {
            "median": float(np.median(sleep_late)), "p99": float(np.percentile(sleep_late, 99)),
            "frames": len(sleep_late),
        },
    }
    if args.json:
        print(json.dumps(fig, indent=2))
        return 0
    d, s = fig["deadline_lateness_us"], fig["plain_sleep_lateness_us"]
    print(f"loop overhead per step (no stages, virtual clock): {overhead:8.2f} us")
    print(f"peer: bare Python call per step:                   {bare:8.2f} us  (loop = {fig['overhead_ratio_vs_bare_call']:.0f}x a bare call)")
    print(f"real clock lateness at the deadline (sleep+spin):  median {d['median']:.1f} us, p99 {d['p99']:.1f} us, max {d['max']:.1f} us  ({d['frames']} frames)")
    f = fig["fixed_2ms_spin"]
    print(f"idle loop's share of a core (learnt spin):        {cpu:5.1f} %  (the fixed 2 ms spin: {f['idle_loop_cpu_percent']:.1f} %, "
          f"lateness median {f['median_lateness_us']:.1f} us, p99 {f['p99_lateness_us']:.1f} us)")
    print(f"peer: plain time.sleep(1/60) lateness:             median {s['median']:.1f} us, p99 {s['p99']:.1f} us  ({s['frames']} frames)")
    return 0
