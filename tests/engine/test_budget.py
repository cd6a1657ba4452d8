"""Budget accounting: percentiles on known durations, overruns per stage and per frame,
the unaccounted slice that makes the parts add up to wall time, the ring buffer."""

from __future__ import annotations

import time

import numpy as np
import pytest

from engine.budget import UNACCOUNTED, WAIT, FrameBudget, percentiles_ms
from engine.clock import VirtualClock
from engine.loop import FixedStepLoop

MS = 1_000_000


def test_percentiles_on_known_durations():
    p = percentiles_ms(np.arange(1, 101) * MS)  # 1..100 ms
    assert p["p50"] == pytest.approx(50.5)
    assert p["p95"] == pytest.approx(95.05)
    assert p["p99"] == pytest.approx(99.01)
    assert p["max"] == 100.0 and p["n"] == 100
    assert percentiles_ms(np.array([], dtype=np.int64))["n"] == 0


def synthetic_budget(frames: list[tuple[list[int], int, int]], **kw) -> FrameBudget:
    """frames: (stage 'a' durations in ms, wait ms, gap ms) per frame; stage 'a' budget 10 ms."""
    b = FrameBudget(**kw)
    a = b.register("a", 10.0)
    t = 0
    for durs, wait, gap in frames:
        b.begin_frame(t)
        start = t
        for d in durs:
            b.add_span(a, 0, t, d * MS)
            t += d * MS + gap * MS  # gap: time between stages nobody measured
        t += wait * MS
        b.end_frame(t, len(durs), 0, wait * MS)
        assert t > start
    return b


def test_summary_per_stage_and_overruns_per_stage_and_frame():
    # 100 frames, one run of 'a' each lasting 1..100 ms
    b = synthetic_budget([([d], 2, 0) for d in range(1, 101)])
    s = b.summary()
    a = s["stages"]["a"]
    assert (a["p50"], a["max"], a["n"]) == (pytest.approx(50.5), 100.0, 100)
    assert a["p99"] == pytest.approx(99.01)
    assert a["overruns"] == 90  # runs longer than its 10 ms budget: 11..100
    assert a["share_p99"] == pytest.approx(99.01 / (1000 / 60))
    assert s["frame_overruns"] == 100 - 16  # work (wall minus wait) over 16.7 ms: 17..100
    assert s["frames"] == 100 and s["steps"] == 100
    assert s["steps_per_frame"] == {"1": 100}
    assert s["stages"][WAIT]["p50"] == pytest.approx(2.0)


def test_unaccounted_makes_the_parts_add_up_to_wall_time():
    b = synthetic_budget([([5, 3], 4, 1), ([2, 2, 2], 0, 3)])
    s = b.summary()
    # frame 0: wall 5+1+3+1+4 = 14, stages 8, wait 4 -> unaccounted 2; frame 1: wall 15, stages 6
    np.testing.assert_allclose(np.sort(b.stage_durations(UNACCOUNTED)) / MS, [2, 9])
    assert s["frame_wall"]["max"] == pytest.approx(15.0)


def test_parts_add_up_exactly_in_a_real_loop():
    clock = VirtualClock()
    loop = FixedStepLoop(clock=clock, auto_freeze_gc=False)
    loop.add_stage("busy", lambda step, dt: sum(range(2000)), budget_ms=1.0)
    loop.add_stage("sleepy", lambda step, dt: time.sleep(0.0002) if step % 7 == 0 else None, budget_ms=1.0)

    def render(alpha: float) -> None:
        with loop.span("render_inner"):
            sum(range(500))

    loop.set_render(render, budget_ms=5.0)
    loop.run(frames=50)
    b = loop.budget
    rows = b.span_rows()
    for f in range(b.frames):
        mine = rows[(b.s_frame[rows] == f) & (b.s_depth[rows] == 0)]
        wall = b.f_end[f] - b.f_start[f]
        assert int(b.s_dur[mine].sum()) == wall  # stages + render + wait + unaccounted, to the ns
    # nested spans are timed but not double-counted
    assert len(b.stage_durations("render_inner")) == 50


def test_stage_overrun_counted_in_a_real_loop():
    loop = FixedStepLoop(clock=VirtualClock(), auto_freeze_gc=False)
    loop.add_stage("slow", lambda step, dt: time.sleep(0.003) if step in (3, 8) else None, budget_ms=2.0)
    loop.run(frames=10)
    assert loop.budget.summary()["stages"]["slow"]["overruns"] == 2  # a sleep never undershoots


def test_ring_keeps_the_last_frames_and_cumulative_counts():
    b = synthetic_budget([([d % 13 + 1], 0, 0) for d in range(50)], capacity_frames=20)
    s = b.summary()
    assert s["frames"] == 50
    assert s["stages"]["a"]["n"] == 20  # only the ring's frames
    assert s["stages"]["a"]["overruns"] == sum(1 for d in range(50) if d % 13 + 1 > 10)
    assert len(b.frame_rows()) == 20


def test_last_frame_ms_for_the_overlay():
    b = synthetic_budget([([4], 1, 0), ([7, 2], 1, 0)])
    last = b.last_frame_ms()
    assert last["a"] == pytest.approx(9.0)
    assert last[WAIT] == pytest.approx(1.0)
