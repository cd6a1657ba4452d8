"""RealClock.wait_until on a scripted time: it never returns before its deadline, and its spin
before the deadline follows how late this system's sleeps wake (the figures of the CPU it saves
come from `quickjab bench loop`, not from a timed test)."""

from __future__ import annotations

import pytest

from engine import clock as clock_module
from engine.clock import SPIN_MIN_NS, SPIN_NS, RealClock

PERIOD_NS = 16_666_667


class ScriptedTime:
    """perf_counter_ns and sleep for engine.clock: a sleep wakes `overshoot_ns` late, each read of
    the counter in the spin costs `tick_ns`; `spun_ns` sums the time spent spinning."""

    def __init__(self, overshoot_ns: int, tick_ns: int = 1000):
        self.now, self.overshoot_ns, self.tick_ns, self.spun_ns = 0, overshoot_ns, tick_ns, 0

    def perf_counter_ns(self) -> int:
        self.now += self.tick_ns
        self.spun_ns += self.tick_ns
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += int(seconds * 1e9) + self.overshoot_ns


@pytest.fixture
def scripted(monkeypatch):
    def install(overshoot_ns: int) -> ScriptedTime:
        t = ScriptedTime(overshoot_ns)
        monkeypatch.setattr(clock_module.time, "perf_counter_ns", t.perf_counter_ns)
        monkeypatch.setattr(clock_module.time, "sleep", t.sleep)
        return t
    return install


def waits(clock: RealClock, t: ScriptedTime, frames: int) -> list[int]:
    """Wait for `frames` deadlines one period apart; how late each wait returned (ns)."""
    late, start = [], t.now
    for k in range(1, frames + 1):
        deadline = start + k * PERIOD_NS
        clock.wait_until(deadline)
        late.append(t.now - deadline)
    return late


def test_the_spin_shrinks_to_its_floor_where_sleeps_wake_on_time(scripted):
    """A fixed 2 ms spin burnt 12 % of a core at 60 Hz on an idle loop; where sleeps overshoot by
    50 us, it shrinks to SPIN_MIN_NS, and no wait returns before its deadline."""
    t = scripted(50_000)
    clock = RealClock()
    assert clock.spin_ns == SPIN_NS
    late = waits(clock, t, 120)
    assert clock.spin_ns == SPIN_MIN_NS
    assert all(0 <= x <= t.tick_ns for x in late)
    t.spun_ns = 0
    waits(clock, t, 60)  # one second at 60 Hz once learnt
    assert t.spun_ns < 60 * (SPIN_MIN_NS + 2 * t.tick_ns)
    assert t.spun_ns / (60 * PERIOD_NS) < 0.02


def test_a_late_wake_up_widens_the_spin_at_once_and_it_shrinks_again(scripted):
    t = scripted(50_000)
    clock = RealClock()
    waits(clock, t, 120)
    t.overshoot_ns = 700_000  # one sleep wakes 0.7 ms late (a busy moment)
    late = waits(clock, t, 1)
    assert late[0] > 0  # that wait itself was late: the spin had been 0.3 ms
    assert clock.spin_ns == 2 * (700_000 + t.tick_ns)  # twice the overshoot (and the counter's read)
    t.overshoot_ns = 50_000
    assert all(x <= t.tick_ns for x in waits(clock, t, 5))  # the wider spin covers the next waits
    waits(clock, t, 60)
    assert clock.spin_ns == SPIN_MIN_NS


def test_the_spin_never_grows_past_spin_ns(scripted):
    """A system whose sleeps wake 5 ms late keeps the old 2 ms spin (and waits late, as before)."""
    t = scripted(5_000_000)
    clock = RealClock()
    waits(clock, t, 10)
    assert clock.spin_ns == SPIN_NS
