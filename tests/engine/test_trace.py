"""The Chrome trace: valid JSON in the Trace Event Format with properly nested events (every
stage inside its frame, spans inside their stage), µs units, required keys, M and C events."""

from __future__ import annotations

import json
import time

import pytest

from engine.budget import FrameBudget
from engine.clock import RealClock, VirtualClock
from engine.errors import InputError
from engine.loop import FixedStepLoop
from engine.trace import chrome_trace, read_chrome_trace, write_chrome_trace

EPS_US = 1e-3  # ts and dur are ns / 1000 in floating point


def traced_loop(clock=None, frames: int = 40, capacity: int = 3600) -> FixedStepLoop:
    clock = clock or VirtualClock()
    loop = FixedStepLoop(clock=clock, auto_freeze_gc=False, budget=FrameBudget(capacity_frames=capacity))

    def sense(step: int, dt: float) -> None:
        with loop.span("sense.decode"):
            with loop.span("sense.decode.crc"):
                sum(range(300))
        if step == 20 and isinstance(clock, VirtualClock):
            clock.stall(150_000_000)  # dropped steps for the counter

    def sleepy(step: int, dt: float) -> None:
        if step % 10 == 0:
            time.sleep(0.002)  # a known lower bound on a duration, to check the units

    loop.add_stage("sense", sense, budget_ms=1.0)
    loop.add_stage("physics", sleepy, budget_ms=1.0)

    def render(alpha: float) -> None:
        with loop.span("render.hud"):
            sum(range(200))

    loop.set_render(render, budget_ms=8.0, name="render")
    loop.run(frames=frames)
    return loop


def check_chrome_trace(doc: dict) -> None:
    """Structural validation of a QuickJab Chrome trace; raises AssertionError."""
    assert isinstance(doc, dict) and isinstance(doc["traceEvents"], list)
    events = doc["traceEvents"]
    for ev in events:
        for key in ("ph", "name", "pid", "tid"):
            assert key in ev, (key, ev)
        assert ev["ph"] in ("X", "C", "M")
        if ev["ph"] in ("X", "C"):
            assert isinstance(ev["ts"], (int, float)) and ev["ts"] >= 0
        if ev["ph"] == "X":
            assert isinstance(ev["dur"], (int, float)) and ev["dur"] >= 0
        if ev["ph"] == "C":
            assert ev["args"] and all(isinstance(v, (int, float)) for v in ev["args"].values())
    meta = {ev["name"] for ev in events if ev["ph"] == "M"}
    assert {"process_name", "thread_name"} <= meta
    counters = {ev["name"] for ev in events if ev["ph"] == "C"}
    assert {"budget", "dropped_steps"} <= counters
    xs = [ev for ev in events if ev["ph"] == "X"]
    frames = [ev for ev in xs if ev["name"] == "frame"]
    assert frames
    # proper nesting on the one thread: any two X events are disjoint or one contains the other
    order = sorted(xs, key=lambda e: (e["ts"], -e["dur"]))
    stack: list[dict] = []
    for ev in order:
        while stack and ev["ts"] >= stack[-1]["ts"] + stack[-1]["dur"] - EPS_US:
            stack.pop()
        if stack:
            parent = stack[-1]
            assert ev["ts"] + ev["dur"] <= parent["ts"] + parent["dur"] + EPS_US, (ev, parent)
        if ev["name"] == "frame":
            assert not stack, "frames do not nest in anything"
        else:
            assert stack and stack[0]["name"] == "frame", f"{ev['name']} outside a frame"
            depth = ev["args"]["depth"]
            assert len(stack) == depth + 1, (ev, [s["name"] for s in stack])
            if depth:
                assert stack[-1]["args"]["depth"] == depth - 1
        stack.append(ev)
    frame_ends = sorted(f["ts"] + f["dur"] for f in frames)
    assert all(a <= b["ts"] + EPS_US for a, b in zip(frame_ends, sorted(frames, key=lambda f: f["ts"])[1:], strict=False))


def test_trace_file_is_valid_chrome_trace_json(tmp_path):
    loop = traced_loop()
    path = tmp_path / "trace.json"
    write_chrome_trace(loop.budget, path)
    doc = json.loads(path.read_text())
    check_chrome_trace(doc)
    xs = [e for e in doc["traceEvents"] if e["ph"] == "X"]
    frames = [e for e in xs if e["name"] == "frame"]
    assert len(frames) == 40
    names = {e["name"] for e in xs}
    assert {"sense", "physics", "render", "wait", "sense.decode", "sense.decode.crc", "render.hud"} <= names
    renders = [e for e in xs if e["args"].get("depth") == 0 and e["name"] not in ("sense", "physics", "wait")]
    assert renders and all(e["name"].startswith("render") for e in renders)
    # one stage event per stage per step
    steps = sum(f["args"]["steps"] for f in frames)
    assert sum(e["name"] == "sense" for e in xs) == steps == loop.step_index
    # the crc span sits two levels down, inside sense.decode, inside sense
    assert all(e["args"]["depth"] == 2 for e in xs if e["name"] == "sense.decode.crc")
    # units are microseconds: a 2 ms sleep lasts at least 2000 and far less than 2e6
    sleeps = [e["dur"] for e in xs if e["name"] == "physics" and e["args"]["step"] % 10 == 0]
    assert sleeps and all(2000 <= d < 1e6 for d in sleeps)
    # the dropped-steps counter ends at the loop's count; frame args carry per-frame drops
    dropped = [e["args"]["dropped"] for e in doc["traceEvents"] if e["ph"] == "C" and e["name"] == "dropped_steps"]
    assert loop.dropped_steps > 0 and dropped[-1] == loop.dropped_steps
    assert sum(f["args"]["dropped"] for f in frames) == loop.dropped_steps
    # the parts of each frame add up to its duration
    for f in frames:
        inside = [e for e in xs if e["name"] != "frame" and e["args"]["depth"] == 0 and f["ts"] <= e["ts"] < f["ts"] + f["dur"]]
        total = sum(e["dur"] for e in inside) + f["args"]["unaccounted_us"]
        assert total == pytest.approx(f["dur"], abs=0.01)


@pytest.mark.parametrize("frames, capacity", [(40, None), (60, 16), (0, None)])
def test_the_written_trace_is_the_trace_as_one_json_text(tmp_path, frames, capacity):
    """The file is written a frame's events at a time (an hour's events as dicts took 64 MB at
    the end of a match); its text is json.dumps of the whole trace, byte for byte: a ring that
    wrapped, and no frames at all, too."""
    loop = traced_loop(frames=frames, capacity=capacity or 3600)
    path = tmp_path / "trace.json"
    write_chrome_trace(loop.budget, path)
    doc = chrome_trace(loop.budget)
    assert len(doc["traceEvents"]) > (2 if frames else 1)
    assert path.read_text() == json.dumps(doc)


def test_trace_of_a_real_clock_run_is_valid(tmp_path):
    loop = traced_loop(clock=RealClock(), frames=6)
    check_chrome_trace(chrome_trace(loop.budget))


def test_trace_after_the_ring_wrapped_is_valid():
    loop = traced_loop(frames=60, capacity=16)
    doc = chrome_trace(loop.budget)
    check_chrome_trace(doc)
    frames = [e for e in doc["traceEvents"] if e["ph"] == "X" and e["name"] == "frame"]
    assert len(frames) == 16 and frames[0]["ts"] == 0
    assert frames[0]["args"]["frame"] == 44


def test_empty_budget_gives_a_valid_but_empty_trace():
    doc = chrome_trace(FrameBudget())
    assert [e["ph"] for e in doc["traceEvents"]] == ["M", "M"]


@pytest.mark.parametrize("content", ["", "{not json", "[1, 2]", '{"traceEvents": 3}',
                                     '{"traceEvents": [{"ph": "X", "name": "a", "ts": "x", "dur": 1}]}',
                                     '{"traceEvents": [{"ph": "M", "name": "process_name"}]}'])
def test_reading_a_bad_trace_names_the_file(tmp_path, content):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(InputError, match="bad.json"):
        read_chrome_trace(path)
    with pytest.raises(InputError, match="missing.json"):
        read_chrome_trace(tmp_path / "missing.json")


_FRAME = '{"ph": "X", "name": "frame", "ts": 0, "dur": 100'


@pytest.mark.parametrize("content", [  # integers no float holds: np.isfinite raised TypeError
    '{"traceEvents": [' + _FRAME + ', "args": {"steps": 1, "dropped": 1' + "0" * 300 + '}}]}',
    '{"traceEvents": [' + _FRAME.replace('"ts": 0', '"ts": 1' + "0" * 400) + '}]}',
    '{"traceEvents": [' + _FRAME + '}, {"ph": "X", "name": "sense", "ts": 1, "dur": 1, "args": {"depth": 1' + "0" * 400 + '}}]}',
    '{"traceEvents": [' + _FRAME + '}], "otherData": {"frame_budget_ms": 1' + "0" * 400 + '}}',
    '{"traceEvents": [' + _FRAME + '}], "otherData": {"stages": {"sense": {"budget_ms": 1' + "0" * 400 + '}}}}',
])
def test_an_integer_no_float_holds_is_refused_naming_the_file(tmp_path, content):
    path = tmp_path / "huge.json"
    path.write_text(content)
    with pytest.raises(InputError, match="huge.json: "):
        read_chrome_trace(path)


_TIMED_COUNTER = '{"ph": "C", "name": "dropped_steps", "ts": 5, "args": {"dropped": 1}}'


@pytest.mark.parametrize("counter", [  # the dropped-steps counter of another writer's trace
    _TIMED_COUNTER.replace('"dropped": 1', '"dropped": Infinity'),  # int(): OverflowError
    _TIMED_COUNTER.replace('"dropped": 1', '"dropped": NaN'),  # int(): ValueError
    _TIMED_COUNTER.replace('"ts": 5', '"ts": "5"') + ", " + _TIMED_COUNTER,  # sorted by ts: TypeError
    _TIMED_COUNTER.replace('"ts": 5', '"ts": null') + ", " + _TIMED_COUNTER,
    _TIMED_COUNTER.replace('"dropped": 1', '"dropped": -7'),  # read as -7 dropped steps
    _TIMED_COUNTER.replace('"dropped": 1', '"dropped": 1e300'),  # read as a 301-digit count
    _TIMED_COUNTER.replace('"dropped": 1', '"dropped": true'),
])
def test_a_dropped_steps_counter_that_is_not_a_count_is_refused_naming_the_event(tmp_path, counter):
    path = tmp_path / "counter.json"
    path.write_text('{"traceEvents": [' + _FRAME + '}, ' + counter + ']}')
    with pytest.raises(InputError, match="counter.json: event 1 .*dropped_steps"):
        read_chrome_trace(path)


def test_read_back_what_was_written(tmp_path):
    loop = traced_loop(frames=10)
    write_chrome_trace(loop.budget, tmp_path / "t.json")
    doc = read_chrome_trace(tmp_path / "t.json")
    assert doc["otherData"]["stages"]["sense"]["budget_ms"] == 1.0


def test_span_ring_wrapping_first_drops_whole_frames_only():
    # ~5 spans per frame but room for 2 per frame: the span ring wraps long before the frame ring
    loop = FixedStepLoop(clock=VirtualClock(), auto_freeze_gc=False,
                         budget=FrameBudget(capacity_frames=50, spans_per_frame=2))
    for name in ("a", "b"):
        loop.add_stage(name, lambda s, dt: None, budget_ms=1.0)
    loop.set_render(lambda a: None, budget_ms=1.0)
    loop.run(frames=80)
    doc = chrome_trace(loop.budget)
    check_chrome_trace(doc)
    frames = [e for e in doc["traceEvents"] if e["ph"] == "X" and e["name"] == "frame"]
    assert 10 <= len(frames) < 50
    stages = [e for e in doc["traceEvents"] if e["ph"] == "X" and e["name"] == "a"]
    assert len(stages) == sum(f["args"]["steps"] for f in frames)  # no frame reported short
    assert loop.budget.summary()["stages"]["a"]["n"] == len(stages)


def test_overruns_are_flagged_in_the_trace():
    loop = FixedStepLoop(clock=VirtualClock(), auto_freeze_gc=False)
    loop.add_stage("slow", lambda step, dt: time.sleep(0.002) if step == 4 else None, budget_ms=1.0)
    loop.run(frames=8)
    xs = [e for e in chrome_trace(loop.budget)["traceEvents"] if e["ph"] == "X" and e["name"] == "slow"]
    assert [e["args"]["step"] for e in xs if e["args"].get("overrun")] == [4]


def test_the_render_event_carries_the_last_step_it_drew():
    """docs/formats.md's example: frame 0's stages and its render are all step 0. The render
    span was booked with the next step's number (frame 0's render said step 1)."""
    doc = chrome_trace(traced_loop(frames=12).budget)
    xs = [e for e in doc["traceEvents"] if e["ph"] == "X"]
    frames = sorted((e for e in xs if e["name"] == "frame"), key=lambda e: e["ts"])
    for f in frames:
        inside = [e for e in xs if e["name"] != "frame" and f["ts"] <= e["ts"] < f["ts"] + f["dur"] + EPS_US]
        steps = [e["args"]["step"] for e in inside if e["name"] == "sense"]
        renders = [e["args"]["step"] for e in inside if e["name"] == "render"]
        if steps:
            assert renders == [max(steps)], (f["args"], steps, renders)


def test_a_span_carries_the_step_of_the_stage_it_nests_in():
    """A span inside the render said the next step's number (frame 0's render.hud said step 1,
    a step not yet run) while its render said step 0; spans inside step stages were right."""
    doc = chrome_trace(traced_loop(frames=12).budget)
    xs = sorted((e for e in doc["traceEvents"] if e["ph"] == "X" and e["name"] != "frame"), key=lambda e: e["ts"])
    stages = [e for e in xs if e["args"]["depth"] == 0]
    spans = [e for e in xs if e["args"]["depth"] >= 1]
    assert {e["name"] for e in spans} == {"sense.decode", "sense.decode.crc", "render.hud"}
    for span in spans:
        parent = [s for s in stages if s["ts"] - EPS_US <= span["ts"] and span["ts"] + span["dur"] <= s["ts"] + s["dur"] + EPS_US]
        assert len(parent) == 1, span
        assert span["args"]["step"] == parent[0]["args"]["step"], (span, parent[0])


_COUNTER = '{"ph": "C", "name": "dropped_steps", "pid": 1, "tid": 1'


def test_a_dropped_steps_counter_that_is_a_count_is_read(tmp_path):
    path = tmp_path / "counter.json"
    path.write_text('{"traceEvents": [' + _FRAME + '}, ' + _COUNTER + ', "ts": 100, "args": {"dropped": 7}}]}')
    assert read_chrome_trace(path)["traceEvents"][1]["args"] == {"dropped": 7}


def test_events_are_written_in_time_order():
    """A span is recorded when it ends, so the ring holds it before the stage (or span) around
    it: the trace listed sense.decode.crc, then sense.decode, then sense, ts going back on the
    thread. Readers that stream events in file order want them in time order, the outer first."""
    doc = chrome_trace(traced_loop(frames=12).budget)
    timed = [e for e in doc["traceEvents"] if e["ph"] in ("X", "C")]
    pairs = list(zip(timed, timed[1:], strict=False))
    assert all(a["ts"] <= b["ts"] for a, b in pairs), [(a["name"], a["ts"], b["name"], b["ts"]) for a, b in pairs if a["ts"] > b["ts"]][:3]
    for a, b in pairs:
        if a["ph"] == b["ph"] == "X" and a["ts"] == b["ts"] and a["name"] != "frame":
            assert a["args"]["depth"] <= b["args"]["depth"], (a, b)


def test_a_span_outside_the_loops_stages_is_not_in_the_trace():
    """`play` draws one frame before the loop starts (game/launch.py: `session.render(0.0)`); a
    span in that draw, or in an `until` callback, was booked to frame 0 with times before it (a
    negative ts) or between frames: an X event inside no frame event, and inside no stage."""
    loop = FixedStepLoop(clock=VirtualClock(), auto_freeze_gc=False)

    def render(alpha: float) -> None:
        with loop.span("render.hud"):
            sum(range(200))

    loop.add_stage("sense", lambda step, dt: None, budget_ms=1.0)
    loop.set_render(render, budget_ms=8.0)
    render(0.0)  # the draw before the loop
    loop.run(frames=5, until=lambda: render(0.0) or False)
    doc = chrome_trace(loop.budget)
    check_chrome_trace(doc)
    hud = [e for e in doc["traceEvents"] if e["ph"] == "X" and e["name"] == "render.hud"]
    assert len(hud) == 5 and all(e["ts"] >= 0 for e in hud)


def _budget_of_awkward_times(frames: int = 400) -> FrameBudget:
    """Frames and spans at nanosecond times whose ns / 1000 is a hair below the decimal (a
    fixed pseudo-random draw), nested as the loop records them: a stage from the frame's start,
    a span inside it ending with it, another stage, and `wait` ending at the frame's end."""
    import random

    rng = random.Random(7)
    budget = FrameBudget(capacity_frames=frames)
    stage, span = budget.register("physics", 1.0), budget.stage_id("physics.collide")
    t = 1_000_000_007
    for step in range(frames):
        start = t
        a = start + rng.randrange(0, 3)  # the first stage starts as its frame does, or nearly
        a_end = a + rng.randrange(50_000, 400_000)
        budget.begin_frame(start)
        budget.add_span(span, step, a + rng.randrange(0, 30_000), a_end - a - 30_000, depth=1)
        budget.add_span(stage, step, a, a_end - a)
        budget.add_span(stage, step, a_end + rng.randrange(0, 5), rng.randrange(1_000, 2_000_000))
        t = start + rng.randrange(16_000_000, 17_000_000)
        budget.end_frame(t, 1, 0, rng.randrange(1_000_000, 10_000_000))
    return budget


def test_every_event_lies_in_its_parent_for_readers_that_truncate_to_nanoseconds():
    """ts and dur are µs as floats; readers such as Perfetto's JSON import take whole ns by
    truncating ts * 1000 and dur * 1000, and ns / 1000 is often a hair below the decimal: ~0.1 %
    of spans came out 1 ns outside their frame. Now every ts and dur truncates back to its
    nanoseconds, ts + dur summed first does too, and the float sums nest as well."""
    budget = _budget_of_awkward_times()
    doc = json.loads(json.dumps(chrome_trace(budget)))  # through the text, as a reader gets it
    xs = [e for e in doc["traceEvents"] if e["ph"] == "X"]
    origin = int(budget.f_start[0])
    starts = {(int(s) - origin, int(d)) for s, d in zip(budget.s_start[:budget.spans], budget.s_dur[:budget.spans], strict=True)}
    starts |= {(int(s) - origin, int(e - s)) for s, e in zip(budget.f_start[:budget.frames], budget.f_end[:budget.frames], strict=True)}
    readers = {
        "truncating ts and dur": lambda e: (int(e["ts"] * 1000), int(e["ts"] * 1000) + int(e["dur"] * 1000)),
        "truncating ts and ts + dur": lambda e: (int(e["ts"] * 1000), int((e["ts"] + e["dur"]) * 1000)),
        "comparing the floats": lambda e: (e["ts"], e["ts"] + e["dur"]),
    }
    for e in xs:  # the nanoseconds come back exact
        assert (int(e["ts"] * 1000), int(e["dur"] * 1000)) in starts, e
    for reader, read in readers.items():
        outside = []
        stack: list[tuple] = []
        for e in xs:
            depth = -1 if e["name"] == "frame" else e["args"]["depth"]
            begin, end = read(e)
            if depth >= 0:
                p_begin, p_end = stack[depth]
                if begin < p_begin or end > p_end:
                    outside.append((e["name"], e["ts"], e["dur"]))
            stack[depth + 1:] = [(begin, end)]
        assert outside == [], (reader, len(outside), outside[:3])
