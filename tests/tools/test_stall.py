"""Budget discipline with the real Session on a VirtualClock: a stall (a 200 ms pause, a GC
pause) inside a stage costs the steps it must drop and nothing more: the next frame catches
up with at most max_steps, the one after is back to one step per frame (no spiral), the stage
overrun is counted, and the trace shows the dropped steps and the overrun."""

from __future__ import annotations

import time

import pytest

from engine.loop import MAX_STEPS_PER_FRAME
from engine.trace import chrome_trace
from tools.scripted_match import build_session

NS = 1_000_000


def stalled_session(match_graph, stall_ms: float, at_steps: set[int], real_ms: float = 0.0):
    """A headless match whose physics stage pauses `stall_ms` of virtual time (and `real_ms` of
    real time, so the stage's wall timer sees it too) at the given steps."""
    s = build_session(seed=1, render=True, size=(320, 180), graph=match_graph)

    def wrap(name, fn):
        if name != "physics":
            return fn

        def stalling(step, dt):
            fn(step, dt)
            if step in at_steps:
                s.clock.stall(int(stall_ms * NS))
                if real_ms:
                    time.sleep(real_ms / 1000)

        return stalling

    s.loop.wrap_stages(wrap)
    return s


def frames_after(s, first_frame: int) -> list[tuple[int, int]]:
    """(steps, dropped) of each recorded frame from first_frame on."""
    b = s.loop.budget
    rows = b.frame_rows()[first_frame:]
    return [(int(b.f_steps[r]), int(b.f_dropped[r])) for r in rows]


def test_a_200ms_stall_drops_what_it_must_and_recovers_within_one_frame(match_graph) -> None:
    s = stalled_session(match_graph, 200.0, {120}, real_ms=200.0)
    s.loop.run(steps=120)  # steps 0..119, one per frame
    assert s.loop.dropped_steps == 0 and s.loop.frame_index == 120
    s.loop.run(frames=1)  # step 120 stalls
    stall_frame = s.loop.frame_index
    s.loop.run(frames=60)
    after = frames_after(s, stall_frame)
    # 200 ms is 12 steps of 1/60 s: the next frame runs max_steps of them and drops the rest ...
    due = 12
    assert after[0] == (MAX_STEPS_PER_FRAME, due - MAX_STEPS_PER_FRAME)
    # ... and every frame after that is an ordinary one: one step, nothing dropped (no spiral)
    assert all(f == (1, 0) for f in after[1:])
    assert s.loop.dropped_steps == due - MAX_STEPS_PER_FRAME
    # simulated time lags the clock by exactly the dropped steps, and keeps pace from then on
    elapsed_steps = round(s.clock.now_ns() * 60 / 1e9)
    assert elapsed_steps - s.loop.step_index == s.loop.dropped_steps
    # the stall is visible: the physics stage overran its budget, the frame overran its period
    stages = {st.name: st for st in s.loop.budget.stages}
    assert stages["physics"].overruns >= 1
    assert s.loop.budget.frame_overruns >= 1
    trace = chrome_trace(s.loop.budget)
    assert trace["otherData"]["dropped_steps"] == due - MAX_STEPS_PER_FRAME
    assert trace["otherData"]["stages"]["physics"]["overruns"] >= 1
    dropped_frames = [e for e in trace["traceEvents"] if e["ph"] == "X" and e["name"] == "frame" and e["args"]["dropped"]]
    assert [e["args"]["dropped"] for e in dropped_frames] == [due - MAX_STEPS_PER_FRAME]
    long_physics = [e for e in trace["traceEvents"] if e["ph"] == "X" and e["name"] == "physics" and e["dur"] > 150_000]
    assert long_physics and long_physics[0]["args"]["step"] == 120
    assert long_physics[0]["args"].get("overrun") is True  # flagged for Perfetto / chrome://tracing


@pytest.mark.parametrize("stall_ms", [1000.0, 5000.0])
def test_a_long_pause_is_clamped_not_replayed(match_graph, stall_ms: float) -> None:
    """A pause longer than the 250 ms clamp (a debugger, a suspended laptop) drops the rest:
    the loop never tries to run seconds of steps after it."""
    s = stalled_session(match_graph, stall_ms, {30})
    s.loop.run(frames=31)
    stall_frame = s.loop.frame_index
    s.loop.run(frames=30)
    after = frames_after(s, stall_frame)
    assert after[0][0] == MAX_STEPS_PER_FRAME
    assert after[0][0] + after[0][1] == round(stall_ms * 60 / 1000)  # every due step ran or was dropped
    assert all(f == (1, 0) for f in after[1:])


def test_repeated_gc_sized_pauses_cost_only_their_own_steps(match_graph) -> None:
    """A 40 ms pause (a full GC on a slow machine) every second: each costs a catch-up frame
    and at most a dropped step or two, the match keeps its pace in between."""
    stalls = set(range(60, 600, 60))
    s = stalled_session(match_graph, 40.0, stalls)
    s.loop.run(frames=600)
    b = s.loop.budget
    rows = b.frame_rows()
    steps = [int(b.f_steps[r]) for r in rows]
    # 40 ms = 2.4 steps: the frame after each pause runs 3 (the fraction carries), the rest 1
    assert max(steps) <= 3
    assert s.loop.dropped_steps == 0
    assert sum(1 for k in steps if k > 1) == len(stalls)
    # nothing lost: the steps run are the time elapsed, up to the accumulator's fraction
    assert abs(s.loop.step_index - s.clock.now_ns() * 60 / 1e9) <= 1
