"""Clocks the loop owns. Both count integer nanoseconds: the real one from
`time.perf_counter_ns` (never pygame's Clock, whose 1 ms ticks give 62.5 Hz), the virtual one
advanced by the loop itself so that headless runs are reproducible to the bit."""

from __future__ import annotations

import time

NS_PER_S = 1_000_000_000
# The step rate, written once: the loop runs at it and everything counted in steps (frames,
# budgets, clip frames, the game's seconds) derives from these three.
STEP_HZ = 60
STEP_DT = 1.0 / STEP_HZ  # seconds per step
STEP_MS = 1000.0 / STEP_HZ  # the frame budget at the step rate
SPIN_NS = 2_000_000  # sleep until ~2 ms before a deadline, then spin: sleep() overshoots


class RealClock:
    virtual = False

    def now_ns(self) -> int:
        return time.perf_counter_ns()

    def seconds(self) -> float:
        return time.perf_counter_ns() / NS_PER_S

    def wait_until(self, deadline_ns: int) -> None:
        remaining = deadline_ns - time.perf_counter_ns()
        if remaining > SPIN_NS:
            time.sleep((remaining - SPIN_NS) / NS_PER_S)
        while time.perf_counter_ns() < deadline_ns:
            pass


class VirtualClock:
    """Time that moves only when told: waiting jumps to the deadline, `stall` injects a pause."""

    virtual = True

    def __init__(self, start_ns: int = 0):
        self.now = start_ns

    def now_ns(self) -> int:
        return self.now

    def seconds(self) -> float:
        return self.now / NS_PER_S

    def advance(self, ns: int) -> None:
        self.now += int(ns)

    stall = advance  # a stage calling clock.stall(120_000_000) simulates a 120 ms hitch

    def wait_until(self, deadline_ns: int) -> None:
        if deadline_ns > self.now:
            self.now = deadline_ns
