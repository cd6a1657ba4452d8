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
# A wait sleeps until a little before its deadline, then spins: sleep() overshoots. The spin is
# learnt: twice the latest overshoot, never under SPIN_MIN_NS nor over SPIN_NS, and otherwise
# shrinking by SPIN_DECAY a wait, so that one late wake-up widens it for half a second. A fixed
# 2 ms spin burnt 12 % of a core at 60 Hz on an idle loop (power and CPU a small board's X server
# wants); Linux overshoots by 0.05-0.1 ms.
SPIN_NS = 2_000_000
SPIN_MIN_NS = 300_000
SPIN_DECAY = 15 / 16  # from 2 ms back to the floor in about 30 waits (half a second)


class RealClock:
    virtual = False

    def __init__(self) -> None:
        self.spin_ns = SPIN_NS  # until the first sleeps have shown how late this system wakes

    def now_ns(self) -> int:
        return time.perf_counter_ns()

    def seconds(self) -> float:
        return time.perf_counter_ns() / NS_PER_S

    def wait_until(self, deadline_ns: int) -> None:
        wake_ns = deadline_ns - self.spin_ns
        now = time.perf_counter_ns()
        if wake_ns > now:
            time.sleep((wake_ns - now) / NS_PER_S)
            late = time.perf_counter_ns() - wake_ns
            self.spin_ns = int(min(SPIN_NS, max(SPIN_MIN_NS, 2 * late, self.spin_ns * SPIN_DECAY)))
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
