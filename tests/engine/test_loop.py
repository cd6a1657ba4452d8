"""The fixed-step loop under a virtual clock: step counts, dropped steps, alpha, stalls,
deadline resets, the 0.25 s clamp, gc.freeze, and bit-reproducible runs."""

from __future__ import annotations

import gc

import numpy as np
import pytest

from engine.clock import NS_PER_S, VirtualClock
from engine.frames import FrameResampler
from engine.loop import MAX_STEPS_PER_FRAME, FixedStepLoop
from engine.sensors import open_source
from engine.state_hash import state_hash

STEP_NS = NS_PER_S / 60


def make_loop(**kw) -> tuple[VirtualClock, FixedStepLoop]:
    clock = VirtualClock()
    return clock, FixedStepLoop(clock=clock, auto_freeze_gc=False, **kw)


def stalling_loop(stall_ms: float, at_step: int) -> tuple[VirtualClock, FixedStepLoop, list[int]]:
    """A loop whose only stage stalls the virtual clock once, at `at_step`; renders log the clock."""
    clock, loop = make_loop()
    render_times: list[int] = []

    def stage(step: int, dt: float) -> None:
        if step == at_step:
            clock.stall(int(stall_ms * 1_000_000))

    loop.add_stage("sim", stage, budget_ms=2.0)
    loop.set_render(lambda alpha: render_times.append(clock.now_ns()), budget_ms=8.0)
    return clock, loop, render_times


def test_one_step_per_frame_at_60hz_and_no_drift():
    clock, loop = make_loop()
    steps: list[int] = []
    loop.add_stage("sim", lambda step, dt: steps.append(step), budget_ms=1.0)
    loop.run(frames=600)
    assert steps == list(range(600))
    assert loop.dropped_steps == 0
    assert loop.alpha < 1e-6
    # 600 frames later the virtual clock is exactly 10 s on: absolute deadlines, no drift
    assert clock.now_ns() == 600 * NS_PER_S // 60
    assert loop.budget.steps_per_frame == {1: 600}


def test_dt_and_step_time_are_exact():
    _, loop = make_loop()
    seen = []
    loop.add_stage("sim", lambda step, dt: seen.append((step, dt)), budget_ms=1.0)
    loop.run(steps=10)
    assert all(dt == 1 / 60 for _, dt in seen)
    assert loop.step_time(6000) == 100.0  # k / hz, not k summed dt's


def test_render_at_25hz_gives_the_interpolation_alpha():
    # 40 ms frames hold 2.4 steps: steps 2,2,3,2,3 and alpha 0.4, 0.8, 0.2, 0.6, 0.0 repeat
    _, loop = make_loop(render_hz=25)
    alphas, counts = [], []
    loop.set_render(lambda a: alphas.append(a), budget_ms=8.0)
    for _ in range(11):
        counts.append(loop.run_frame())
    assert counts == [1, 2, 2, 3, 2, 3, 2, 2, 3, 2, 3]
    np.testing.assert_allclose(alphas, [0, 0.4, 0.8, 0.2, 0.6, 0, 0.4, 0.8, 0.2, 0.6, 0], atol=1e-9)
    assert loop.dropped_steps == 0


def test_render_at_30hz_runs_two_steps_per_frame():
    _, loop = make_loop(render_hz=30)
    loop.run(frames=100)
    assert loop.budget.steps_per_frame == {1: 1, 2: 99}
    assert loop.budget.frame_period_ms == pytest.approx(1000 / 30)


def test_120ms_stall_catches_up_at_most_5_steps_and_counts_the_rest():
    clock, loop, _ = stalling_loop(120, at_step=10)
    per_frame = [loop.run_frame() for _ in range(14)]
    # frames 0..10 run one step each; step 10 stalls 120 ms = 7.2 steps: 5 run, 2 dropped
    assert per_frame[:11] == [1] * 11
    assert per_frame[11] == MAX_STEPS_PER_FRAME
    assert loop.dropped_steps == 2
    assert loop.budget.f_dropped[11] == 2
    assert loop.alpha == pytest.approx(0.2, abs=1e-6)  # the 0.2 step left over is carried
    assert per_frame[12:] == [1, 1]  # back to normal at once
    # every step of elapsed time is accounted: run + dropped + the fraction carried in alpha
    # (after a frame's wait the clock sits at the next step's instant)
    total = loop.step_index + loop.dropped_steps + loop.alpha
    assert total == pytest.approx(clock.now_ns() / STEP_NS, abs=1e-6)


def test_200ms_stall_drops_what_it_must_and_recovers_within_one_frame():
    _, loop, _ = stalling_loop(200, at_step=30)
    per_frame = [loop.run_frame() for _ in range(40)]
    assert per_frame[31] == 5  # 12 steps due
    assert loop.dropped_steps == 7
    assert per_frame[32:] == [1] * 8  # the very next frame is a normal one: no spiral
    assert loop.budget.dropped_steps == 7


def test_deadlines_reset_after_a_stall():
    clock, loop, renders = stalling_loop(200, at_step=5)
    for _ in range(12):
        loop.run_frame()
    gaps = np.diff(renders)
    assert loop.stalls == 1
    # before: one frame period apart; the stall frame renders 200 ms late; the catch-up frame
    # follows at once; after it the frames are one period apart again, measured from the
    # stall (no burst of zero-wait frames chasing the old schedule)
    assert set(gaps[:4].tolist()) <= {16_666_666, 16_666_667}
    assert gaps[4] == 200_000_000 + 16_666_667
    assert gaps[5] == 0
    assert set(gaps[6:].tolist()) <= {16_666_666, 16_666_667}


def test_short_hitch_keeps_the_absolute_schedule():
    # a 10 ms hitch is less than a frame late: the next deadline stays where it was
    clock, loop, renders = stalling_loop(10, at_step=5)
    for _ in range(10):
        loop.run_frame()
    assert loop.stalls == 0
    assert renders[5] - renders[0] == pytest.approx(5 * STEP_NS + 10e6, abs=2)  # the hitch frame
    assert renders[6] - renders[0] == pytest.approx(6 * STEP_NS, abs=2)  # back on the k/60 grid
    assert clock.now_ns() == -(-10 * NS_PER_S // 60)
    assert loop.dropped_steps == 0


def test_frame_time_is_clamped_at_a_quarter_second():
    clock, loop, _ = stalling_loop(1000, at_step=3)
    per_frame = [loop.run_frame() for _ in range(6)]
    assert per_frame[4] == 5
    # 1 s = 60 steps: 15 due after the clamp (5 run, 10 dropped) and 45 cut off by the clamp
    assert loop.dropped_steps == 55
    assert per_frame[5] == 1


def test_run_stops_on_steps_frames_until_and_stop():
    _, loop = make_loop()
    loop.run(steps=7)
    assert loop.step_index == 7
    loop.run(frames=3)
    assert loop.frame_index == 10
    loop.add_stage("stopper", lambda step, dt: loop.stop() if step == 20 else None, budget_ms=1.0)
    loop.run()
    assert loop.step_index == 21
    loop.run(until=lambda: loop.step_index >= 25)
    assert loop.step_index == 25


def test_render_stage_name_must_start_with_render():
    _, loop = make_loop()
    with pytest.raises(ValueError):
        loop.set_render(lambda a: None, budget_ms=1.0, name="draw")
    loop.set_render(lambda a: None, budget_ms=1.0, name="render_hud")


def test_gc_is_frozen_once_when_run_starts(monkeypatch):
    calls = []
    monkeypatch.setattr(gc, "freeze", lambda: calls.append("freeze"))
    _, loop = make_loop()
    loop.run(frames=2)
    assert calls == []  # auto_freeze_gc=False
    loop = FixedStepLoop(clock=VirtualClock())
    loop.run(frames=2)
    loop.run(frames=2)
    assert calls == ["freeze"] and loop.gc_frozen


def test_gc_freeze_really_moves_objects_to_the_permanent_generation():
    gc.unfreeze()
    assert gc.get_freeze_count() == 0
    assets = [list(range(10)) for _ in range(1000)]  # "loaded assets"
    FixedStepLoop(clock=VirtualClock()).run(frames=1)
    try:
        assert gc.get_freeze_count() >= len(assets)
    finally:
        gc.unfreeze()


def headless_run(steps: int, stall_at: int | None = None) -> str:
    """A small simulation on a replayable source: integrate the frames, hash the state."""
    clock = VirtualClock()
    source = open_source("demo://?rate=430", clock=clock.seconds)
    loop = FixedStepLoop(clock=clock, auto_freeze_gc=False)
    res = FrameResampler(sensors=2)
    vel = np.zeros(6)
    pos = np.zeros(6)

    def sense(step: int, dt: float) -> None:
        res.push(source.poll())

    def simulate(step: int, dt: float) -> None:
        if step == stall_at:
            clock.stall(150_000_000)
        frame = res.frame_at(loop.step_time(step) - 0.01)
        if frame is not None:
            vel[:] += frame * dt
            pos[:] += vel * dt

    loop.add_stage("sense", sense, budget_ms=1.0)
    loop.add_stage("simulate", simulate, budget_ms=1.0)
    loop.run(steps=steps)
    return state_hash(pos, vel, loop.step_index, loop.dropped_steps, clock.now_ns())


def test_two_headless_runs_give_the_same_state_hash():
    a = headless_run(600, stall_at=200)
    b = headless_run(600, stall_at=200)
    assert a == b
    # and the hash does tell runs apart
    assert headless_run(600, stall_at=300) != a
    assert headless_run(601, stall_at=200) != a


def test_state_hash_covers_dtype_shape_and_values():
    x = np.arange(6, dtype=np.float64)
    assert state_hash(x) == state_hash(x.copy())
    assert state_hash(x) != state_hash(x.astype(np.float32))
    assert state_hash(x) != state_hash(x.reshape(2, 3))
    y = x.copy()
    y[3] = np.nextafter(y[3], 10)
    assert state_hash(x) != state_hash(y)


def test_resync_after_a_pause_drops_nothing():
    clock, loop = make_loop()
    loop.run(frames=10)
    clock.advance(5 * NS_PER_S)  # the game was paused outside the loop
    loop.resync()
    assert loop.run_frame() == 0  # no catch-up burst; the accumulator keeps its fraction
    assert loop.dropped_steps == 0
    loop.run(frames=5)
    assert loop.step_index == 15 and loop.dropped_steps == 0


def test_run_steps_is_exact_even_when_a_frame_owes_catch_up_steps():
    clock = VirtualClock()
    loop = FixedStepLoop(clock=clock)
    seen = []

    def stage(step: int, dt: float) -> None:
        seen.append(step)
        if step == 8:
            clock.stall(70_000_000)  # the next frame owes 5 steps; only 2 are left to run

    loop.add_stage("s", stage, 1.0)
    loop.run(steps=10)
    assert loop.step_index == 10 and seen == list(range(10))
    assert loop.dropped_steps == 0 and 0.0 <= loop.alpha <= 1.0


@pytest.mark.parametrize("render_hz", [60, 30, 25])
def test_how_run_steps_is_split_does_not_change_the_clock_any_step_sees(render_hz):
    """`run(steps=N)` in one call or in calls of any size: every step runs at the same clock
    reading, so a headless run's state cannot depend on how a tool splits it. A frame cut short
    by the steps left does not wait for its deadline: the next call's first frame runs the held
    steps at the same reading. Before, it waited: at 30 Hz, 7-step calls ran every seventh step
    a frame late (the low-power scripted match's state hash changed with the split)."""

    def seen(chunks: list[int]) -> tuple[list[tuple[int, int]], int, int]:
        clock, loop = make_loop(render_hz=render_hz)
        log: list[tuple[int, int]] = []

        def stage(step: int, dt: float) -> None:
            log.append((step, clock.now_ns()))
            if step == 40:
                clock.stall(120_000_000)  # catch-up frames of several steps, split too

        loop.add_stage("s", stage, 1.0)
        for n in chunks:
            loop.run(steps=n)
        assert loop.step_index == sum(chunks)
        return log, loop.dropped_steps, clock.now_ns()

    whole = seen([120])
    assert seen([7] * 17 + [1]) == whole
    assert seen([1] * 120) == whole
    assert seen([3, 38, 1, 1, 77]) == whole


@pytest.mark.parametrize("stall_ms", [260, 1010, 5_008.4])
def test_a_stall_past_the_clamp_accounts_for_every_step_too(stall_ms):
    """A hitch longer than the 250 ms clamp: the whole steps the clamp cut off were dropped but
    the fraction of a step beyond them was neither run, dropped nor carried (a 260 ms hitch, 15.6
    steps: 5 run, 10 dropped, 0.6 gone), so run + dropped no longer added up to the time passed."""
    clock, loop, _ = stalling_loop(stall_ms, at_step=3)
    for _ in range(8):
        loop.run_frame()
    assert loop.dropped_steps > 0
    total = loop.step_index + loop.dropped_steps + loop.alpha
    assert total == pytest.approx(clock.now_ns() / STEP_NS, abs=1e-6)


class LateWakeClock(VirtualClock):
    """A virtual clock whose `at_wait`-th wait returns `late_ns` after its deadline: a sleep that
    overslept (the OS ran something else) rather than a stage that stalled."""

    def __init__(self, late_ns: int, at_wait: int):
        super().__init__()
        self.late_ns, self.at_wait, self.waits = late_ns, at_wait, 0

    def wait_until(self, deadline_ns: int) -> None:
        super().wait_until(deadline_ns)
        self.waits += 1
        if self.waits == self.at_wait:
            self.now += self.late_ns


@pytest.mark.parametrize("late_ms", [20, 70, 120, 200])
@pytest.mark.parametrize("render_hz, per_frame", [(60, 1), (30, 2)])
def test_a_late_wake_up_is_caught_up_by_one_frame_and_no_frame_runs_no_step(
    late_ms, render_hz, per_frame
):
    clock = LateWakeClock(late_ms * 1_000_000, at_wait=3)
    loop = FixedStepLoop(clock=clock, render_hz=render_hz, auto_freeze_gc=False)
    steps: list[int] = []
    loop.add_stage("sim", lambda step, dt: steps.append(step), budget_ms=1.0)
    counts = [loop.run_frame() for _ in range(12)]
    # the frame after the late wait runs what is due (the catch-up); the next one waits for the
    # next step instead of rendering the same state again, then frames are normal
    assert 0 not in counts
    assert counts[3] > per_frame
    assert counts[-6:] == [per_frame] * 6
    assert steps == list(range(len(steps)))
    # every step of the time passed is run, dropped or carried: none lost by the wait (the clock
    # sits a frame past the last frame's reading; the first frame ran one step at 0)
    total = loop.step_index + loop.dropped_steps + loop.alpha
    assert total == pytest.approx(clock.now_ns() / STEP_NS + 1 - per_frame, abs=1e-6)
