"""`quickjab profile`: the summary of a trace agrees with the loop's own budget summary, the
table and JSON print, --plot draws a PNG, and bad traces give one line and exit code 2."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from engine.clock import VirtualClock
from engine.loop import FixedStepLoop
from engine.trace import read_chrome_trace, write_chrome_trace
from tools.cli import main
from tools.profile import profile_summary


@pytest.fixture(scope="module")
def traced(tmp_path_factory):
    clock = VirtualClock()
    loop = FixedStepLoop(clock=clock, auto_freeze_gc=False, render_hz=30)

    def physics(step: int, dt: float) -> None:
        with loop.span("physics.collide"):
            sum(range(1000))
        if step in (50, 51, 52):
            time.sleep(0.0015)  # over its 1 ms budget: three overruns
        if step == 100:
            clock.stall(200_000_000)

    loop.add_stage("physics", physics, budget_ms=1.0)
    loop.add_stage("recognize", lambda s, dt: sum(range(300)), budget_ms=0.5)
    loop.set_render(lambda a: sum(range(3000)), budget_ms=8.0)
    loop.run(frames=120)
    path = tmp_path_factory.mktemp("trace") / "trace.json"
    write_chrome_trace(loop.budget, path)
    return loop, path


def test_summary_matches_the_loops_budget(traced):
    loop, path = traced
    s = profile_summary(read_chrome_trace(path))
    b = loop.budget.summary()
    assert s["frames"] == b["frames"] == 120
    assert s["steps"] == b["steps"] == loop.step_index
    assert s["dropped_steps"] == b["dropped_steps"] == loop.dropped_steps > 0
    assert s["steps_per_frame"] == b["steps_per_frame"]
    assert s["frame_period_ms"] == pytest.approx(1000 / 30)
    for name in ("physics", "recognize", "render", "wait", "unaccounted", "physics.collide"):
        for key in ("p50", "p95", "p99", "max"):
            assert s["stages"][name][key] == pytest.approx(b["stages"][name][key], abs=1e-6), (name, key)
    assert s["stages"]["physics"]["overruns"] == b["stages"]["physics"]["overruns"] >= 3
    assert s["stages"]["physics.collide"]["nested"] and not s["stages"]["physics"]["nested"]


def test_table_and_json(traced, capsys):
    _, path = traced
    assert main(["profile", str(path)]) == 0
    out = capsys.readouterr().out
    for word in ("physics", "recognize", "render", "unaccounted", "p99", "steps per frame", "dropped steps"):
        assert word in out
    assert main(["profile", str(path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["frames"] == 120 and doc["stages"]["render"]["n"] == 120


def test_plot_draws_a_png(traced, tmp_path, capsys):
    _, path = traced
    png = tmp_path / "profile.png"
    assert main(["profile", str(path), "--plot", str(png)]) == 0
    import matplotlib.image as mpimg

    img = mpimg.imread(png)
    assert img.shape[0] > 300 and img.shape[1] > 800
    assert np.unique(img.reshape(-1, img.shape[2]), axis=0).shape[0] > 20  # more than a blank canvas


@pytest.mark.parametrize("name, written", [("noext", "noext.png"), ("dot.", "dot.png"), ("p.svg", "p.svg")])
def test_a_plot_says_the_file_it_wrote(traced, tmp_path, capsys, name, written):
    """`--plot p/noext` wrote noext.png without a word (matplotlib adds its default format's
    suffix), and no plot said where it went, as other commands' outputs do."""
    _, path = traced
    out = tmp_path / "p" / name
    assert main(["profile", str(path), "--plot", str(out), "--json"]) == 0
    stdout, err = capsys.readouterr()
    json.loads(stdout)  # the JSON alone on stdout
    assert err.splitlines() == [f"quickjab profile: wrote {tmp_path / 'p' / written}"]
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == [written]


def test_a_plot_matplotlib_cannot_write_is_refused_before_the_summary(traced, tmp_path, capsys):
    _, path = traced
    with pytest.raises(SystemExit) as exit_:  # was a ValueError traceback after the summary
        main(["profile", str(path), "--plot", str(tmp_path / "p.xyz")])
    out, err = capsys.readouterr()
    assert exit_.value.code == 2 and out == "" and len(err.strip().splitlines()) == 1 and "p.xyz" in err, err


@pytest.mark.parametrize("content", ["{broken", '{"traceEvents": []}', "[]", '{"foo": 1}'])
def test_bad_trace_is_one_line_and_exit_2(tmp_path, capsys, content):
    path = tmp_path / "bad_trace.json"
    path.write_text(content)
    assert main(["profile", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad_trace.json" in err[0]


def test_plot_uses_the_frame_period_and_is_not_flattened_by_an_outlier(tmp_path):
    """Issue 17: a first frame of 300 ms flattened the plots, and a 30 Hz (low power) trace
    drew the 16.7 ms line where its frames have 33.3 ms."""
    clock = VirtualClock()
    loop = FixedStepLoop(clock=clock, auto_freeze_gc=False, render_hz=30)

    def render(alpha: float) -> None:
        if loop.frame_index == 0:
            time.sleep(0.3)  # the start-up outlier
        else:
            time.sleep(0.002)

    loop.add_stage("physics", lambda s, dt: sum(range(300)), budget_ms=1.0)
    loop.set_render(render, budget_ms=4.0)
    loop.run(frames=80)
    path = tmp_path / "t.json"
    write_chrome_trace(loop.budget, path)
    from tools.profile import plot_profile

    trace = read_chrome_trace(path)
    limits = plot_profile(trace, profile_summary(trace), str(tmp_path / "p.png"))
    assert limits["period_ms"] == pytest.approx(1000 / 30, abs=0.05)
    assert limits["hist_xmax"] < 100 and limits["bars_ymax"] < 100  # not stretched to 300 ms
    assert limits["hist_xmax"] >= limits["period_ms"]


def test_a_plot_of_thousands_of_stages_draws_the_largest_and_sums_the_rest(tmp_path):
    """One filled band and one legend entry per stage name: 2000 names (a 100 KB trace) took
    10 s to draw, 50,000 (1.6 MB) minutes. The largest stages are drawn, the rest as one band."""
    from tools.profile import MAX_PLOT_STAGES, plot_profile

    frame = {"ph": "X", "name": "frame", "ts": 0, "dur": 10_000, "args": {"steps": 1}}
    # one after the other (a span inside another is nested in it, docs/formats.md)
    stages = [{"ph": "X", "name": f"s{i}", "ts": 1 + 3 * i, "dur": 1 + i % 2} for i in range(3000)]
    stages.append({"ph": "X", "name": "physics", "ts": 9100, "dur": 800})
    path = tmp_path / "many.json"
    path.write_text(json.dumps({"traceEvents": [frame, *stages]}))
    trace = read_chrome_trace(path)
    limits = plot_profile(trace, profile_summary(trace), str(tmp_path / "p.png"))
    assert len(limits["stages"]) == MAX_PLOT_STAGES and limits["stages"][0] == "physics"
    n, rest = limits["stages"][-1].split(" ", 1)  # the rest, with the loop's own "unaccounted" time
    assert rest == "other stages" and int(n) >= 3001 - (MAX_PLOT_STAGES - 1)


def test_a_trace_from_another_writer_is_read_by_the_contract_alone(tmp_path):
    """docs/formats.md says what a trace holds: stage events, one per stage per step, inside a
    `frame` event; spans inside a stage nest inside it; a `C` counter of dropped steps. A trace
    written by another tool (no `steps`, `dropped` or `depth` args, which this project's writer
    adds) read as 0 steps, 0 dropped, and its nested span as a stage of its own."""
    from tools.profile import profile_summary

    ev = []
    for ts, dropped in ((0, 0), (20_000, 3)):
        ev.append({"ph": "X", "name": "frame", "ts": ts, "dur": 16_000, "pid": 1, "tid": 1})
        for step in range(2):
            at = ts + 100 + 5000 * step
            ev.append({"ph": "X", "name": "physics", "ts": at, "dur": 3000, "pid": 1, "tid": 1})
            ev.append({"ph": "X", "name": "solver", "ts": at + 500, "dur": 1000, "pid": 1, "tid": 1})
        ev.append({"ph": "X", "name": "render_scene", "ts": ts + 11_000, "dur": 4000, "pid": 1, "tid": 1})
        ev.append({"ph": "C", "name": "dropped_steps", "ts": ts + 16_000, "pid": 1, "tid": 1, "args": {"dropped": dropped}})
    ev.append({"ph": "M", "name": "process_name", "pid": 1, "tid": 1, "args": {"name": "other tool"}})
    path = tmp_path / "other.json"
    for order in (ev, ev[::-1]):
        path.write_text(json.dumps({"traceEvents": order}))
        s = profile_summary(read_chrome_trace(path))
        assert (s["frames"], s["steps"], s["dropped_steps"], s["steps_per_frame"]) == (2, 4, 3, {"2": 2})
        assert s["stages"]["solver"]["nested"] and not s["stages"]["physics"]["nested"]
        assert s["stages"]["physics"]["n"] == 4 and s["stages"]["solver"]["n"] == 4


def test_a_trace_that_does_not_say_its_unaccounted_time_gets_no_row_of_zeros(tmp_path, capsys):
    """`unaccounted_us` is this project's frame arg, not the contract's: a trace without it
    (another writer's) was summarized with an `unaccounted` row of 0.000 ms in every column,
    a measurement nobody made. This project's traces keep the row."""
    ev = [{"ph": "X", "name": "frame", "ts": 0, "dur": 16_000, "pid": 1, "tid": 1},
          {"ph": "X", "name": "physics", "ts": 100, "dur": 3000, "pid": 1, "tid": 1},
          {"ph": "X", "name": "render", "ts": 11_000, "dur": 4000, "pid": 1, "tid": 1}]
    path = tmp_path / "other.json"
    path.write_text(json.dumps({"traceEvents": ev}))
    s = profile_summary(read_chrome_trace(path))
    assert set(s["stages"]) == {"physics", "render"}
    assert main(["profile", str(path)]) == 0
    assert "unaccounted" not in capsys.readouterr().out
    assert "unaccounted" in profile_summary(read_chrome_trace(traced_path(tmp_path)))["stages"]


def traced_path(tmp_path) -> str:
    loop = FixedStepLoop(clock=VirtualClock(), auto_freeze_gc=False)
    loop.add_stage("physics", lambda s, dt: None, budget_ms=1.0)
    loop.run(frames=3)
    path = tmp_path / "own.json"
    write_chrome_trace(loop.budget, path)
    return str(path)


def test_a_trace_that_holds_the_last_frames_of_a_longer_run_says_so(tmp_path, capsys):
    """The loop keeps its last 3600 frames (a minute): `play --trace` after ten minutes wrote
    3600 frames of 36,618 and `profile` printed "3600 frames" with nothing to say the rest of
    the run is not in it (otherData.frames_total says it)."""
    from engine.budget import FrameBudget

    loop = FixedStepLoop(clock=VirtualClock(), auto_freeze_gc=False, budget=FrameBudget(capacity_frames=10))
    loop.add_stage("physics", lambda s, dt: None, budget_ms=1.0)
    loop.run(frames=25)
    path = tmp_path / "ring.json"
    write_chrome_trace(loop.budget, path)
    s = profile_summary(read_chrome_trace(path))
    assert (s["frames"], s["frames_total"]) == (10, 25)
    assert main(["profile", str(path)]) == 0
    assert capsys.readouterr().out.splitlines()[0].startswith("10 frames (the last of 25 run), 10 steps")
    whole = traced_path(tmp_path)  # a run the trace holds whole: the line as before
    assert profile_summary(read_chrome_trace(whole))["frames_total"] == 3
    assert main(["profile", whole]) == 0
    assert capsys.readouterr().out.startswith("3 frames, 3 steps")


@pytest.mark.parametrize("field, value", [
    ("frames_total", -3), ("frames_total", 2.5), ("frames_total", "many"), ("frames_total", True),
    ("frames_total", 10**400), ("frames_total", 1e400), ("dropped_steps", -1), ("frame_overruns", 10**13),
    ("frame_budget_ms", 1e300), ("frame_budget_ms", 1e-300), ("frame_period_ms", 1e300), ("frame_period_ms", 1e-300),
])
def test_a_run_figure_out_of_its_range_is_refused_naming_the_file_and_the_field(tmp_path, capsys, field, value):
    """A hostile trace's otherData: a frames_total of -3 was ignored without a word, a budget or
    period of 1e300 or 1e-300 printed 300-digit numbers and garbled the table's header."""
    doc = json.loads(open(traced_path(tmp_path)).read())
    doc["otherData"][field] = value
    path = tmp_path / "odd.json"
    path.write_text(json.dumps(doc))
    assert main(["profile", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and err.startswith(f"quickjab profile: {path}: otherData.{field} "), err
    assert len(err) < 200, err


@pytest.mark.parametrize("where, value", [("steps", 1e9), ("steps", 1001), ("budget_ms", 1e300)])
def test_a_frames_steps_or_a_stage_budget_out_of_range_is_refused(tmp_path, capsys, where, value):
    """A frame's args.steps of 1e9 made "1000000299 steps"; a stage's budget of 1e300 a 300-digit
    column. A frame runs at most a few steps (the loop's max_steps)."""
    doc = json.loads(open(traced_path(tmp_path)).read())
    if where == "steps":
        next(e for e in doc["traceEvents"] if e.get("name") == "frame")["args"]["steps"] = value
    else:
        next(iter(doc["otherData"]["stages"].values()))["budget_ms"] = value
    path = tmp_path / "odd.json"
    path.write_text(json.dumps(doc))
    assert main(["profile", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and str(path) in err, err
    assert ("args.steps" if where == "steps" else "budget_ms") in err and len(err) < 200, err


def test_a_plausible_trace_of_a_slow_loop_is_still_read(tmp_path):
    doc = json.loads(open(traced_path(tmp_path)).read())
    doc["otherData"].update(frame_budget_ms=1000.0, frame_period_ms=1000.0)  # a 1 Hz loop
    path = tmp_path / "slow.json"
    path.write_text(json.dumps(doc))
    assert profile_summary(read_chrome_trace(path))["frame_period_ms"] == 1000.0


def test_a_stage_as_long_as_its_frame_is_read_inside_it_whatever_the_order(tmp_path):
    """Another writer's stage that starts and ends with its `frame` event (a frame of one stage,
    or whole-microsecond times) and is listed before it was read as the frame's parent: the
    frame then held 0 steps. docs/formats.md: stages nest inside the `frame` event."""
    ev = []
    for k in range(3):
        ev += [{"ph": "X", "name": "sim", "ts": k * 20_000, "dur": 16_000, "pid": 1, "tid": 1},
               {"ph": "X", "name": "frame", "ts": k * 20_000, "dur": 16_000, "pid": 1, "tid": 1}]
    path = tmp_path / "tie.json"
    for order in (ev, ev[::-1]):
        path.write_text(json.dumps({"traceEvents": order}))
        s = profile_summary(read_chrome_trace(path))
        assert (s["frames"], s["steps"], s["steps_per_frame"]) == (3, 3, {"1": 3})
        assert not s["stages"]["sim"]["nested"]


def test_a_trace_of_the_last_frames_gives_the_whole_runs_dropped_steps_and_overruns_too(tmp_path, capsys):
    """After a stall early in a long run the F3 overlay said "dropped 7" and `profile` of the
    trace written at the end "0 dropped steps", the stall's frame having left the ring; the run's
    totals are in otherData and now beside the held frames' figures."""
    from engine.budget import FrameBudget

    clock = VirtualClock()
    loop = FixedStepLoop(clock=clock, auto_freeze_gc=False, budget=FrameBudget(capacity_frames=10))

    def physics(step: int, dt: float) -> None:
        if step == 3:
            clock.stall(200_000_000)
            time.sleep(0.02)  # over the frame's period too

    loop.add_stage("physics", physics, budget_ms=1.0)
    loop.run(frames=25)
    path = tmp_path / "ring.json"
    write_chrome_trace(loop.budget, path)
    s = profile_summary(read_chrome_trace(path))
    assert (s["dropped_steps"], s["run_dropped_steps"]) == (0, loop.dropped_steps) and loop.dropped_steps > 0
    assert (s["frame_overruns"], s["run_frame_overruns"]) == (0, loop.budget.frame_overruns) and loop.budget.frame_overruns > 0
    assert main(["profile", str(path)]) == 0
    out = capsys.readouterr().out
    assert f"0 dropped steps ({loop.dropped_steps} in the whole run)" in out.splitlines()[0]
    assert f"0 frames over 16.7 ms ({loop.budget.frame_overruns} in the whole run)" in out


def test_the_share_column_says_what_it_is_a_share_of(traced, capsys):
    """The column of p99 as a share of the 16.7 ms step budget was headed `p99/budget`, beside
    the `budget` column of the stage's own budget, and the F3 overlay's `p99 / budget` is the p99
    against that stage budget: input's p99 of 0.50 ms over its 0.30 read "3.0%"."""
    _, path = traced
    assert main(["profile", str(path)]) == 0
    header = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("stage"))
    assert "p99/16.7ms" in header and "p99/budget" not in header


def test_a_trace_of_no_frames_says_the_run_ended_before_its_first(tmp_path, capsys):
    """`play --trace` interrupted before its first frame writes a trace of none (otherData's
    frames_total 0): profile called it "not written by a QuickJab loop?", which it was."""
    from engine.budget import FrameBudget

    path = tmp_path / "t.json"
    write_chrome_trace(FrameBudget(), path)
    assert main(["profile", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"quickjab profile: {path}: no frames: the run ended before its first frame"]
