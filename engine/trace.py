"""Export a FrameBudget to the Chrome Trace Event Format (docs/formats.md), and read one back.

One `frame` X event per rendered frame; inside it one X event per stage per step, the render
stage (its name starts with `render`) and `wait`; spans inside a stage nest in it. A stage
run over its declared budget carries `"overrun": true` in its args, a frame whose work
exceeded the frame period too. The frame's
`unaccounted` time (the loop's own bookkeeping between stages) is scattered in small gaps, so
it goes into the frame event's args rather than as an X event that would overlap its
neighbours. C events carry the frame's budget use and the dropped-step count; M events name
the process and thread. Times are microseconds from the first recorded frame.
"""

from __future__ import annotations

import json
import math
import os
import stat
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from engine.budget import UNACCOUNTED, FrameBudget
from engine.errors import InputError
from engine.npz_files import write_replacing

PID, TID = 1, 1


class TraceError(InputError):
    """A trace file that cannot be read as a QuickJab Chrome trace; names the file."""


def _us(ns: int) -> float:
    """`ns` in microseconds: the float next to ns / 1000 whose product with 1000 truncates back
    to `ns`. The float nearest ns / 1000 is often a hair below it (0.001 has no exact binary
    form), and readers that truncate ts * 1000 and dur * 1000 to whole nanoseconds (Perfetto's
    JSON import) then put ~0.1 % of spans 1 ns outside their frame, which in nanoseconds they
    never are: from these, ts and dur come back exact, and so does the nesting."""
    us = ns / 1000
    while int(us * 1000) != ns:  # a few ulps at most: the next float up (down below zero)
        us = math.nextafter(us, math.copysign(math.inf, ns))
    return us


def _ts_dur(start_ns: int, end_ns: int) -> tuple[float, float]:
    """An X event's ts and dur (µs) from its start and end (ns from the origin): each truncates
    back to its nanoseconds (_us), and ts + dur summed in floating point reaches _us(end_ns), so
    that readers that add before truncating get the end's nanoseconds back too."""
    ts = _us(start_ns)
    return ts, _lengthened(ts, _us(end_ns - start_ns), _us(end_ns))


def _lengthened(ts: float, dur: float, end: float) -> float:
    """dur, lengthened by the few ulps (far below 1 ns: it truncates as before) that let
    ts + dur, in floating point, reach `end`."""
    for _ in range(4):  # one step, or two where the sum rounds
        total = ts + dur
        if total >= end:
            break
        dur += end - total
    return dur


def _enclose(open_events: list[dict], event: dict) -> None:
    """Let every event `event` nests in end, as a float sum, no earlier than it: a stage ending
    in the nanosecond its frame ends (`wait`) may have the larger sum of the two by an ulp, which
    a reader comparing ts + dur saw as a span leaving its frame."""
    end = event["ts"] + event["dur"]
    for parent in reversed(open_events):
        parent["dur"] = _lengthened(parent["ts"], parent["dur"], end)
        end = parent["ts"] + parent["dur"]


def chrome_trace(budget: FrameBudget) -> dict:
    """The frames and spans `budget` holds as a Chrome trace (a dict ready for json.dumps)."""
    events = [event for batch in _event_batches(budget) for event in batch]
    return {"traceEvents": events, "displayTimeUnit": "ms", "otherData": _other_data(budget)}


def _trace_text(budget: FrameBudget) -> Iterator[str]:
    """json.dumps(chrome_trace(budget)), the same text, a frame's events at a time: the whole
    list of an hour's events as dicts took 64 MB more at the end of a `play --trace` (a lot on a
    small board), one frame's a few kB."""
    yield '{"traceEvents": ['
    sep = ""
    for batch in _event_batches(budget):
        if batch:
            yield sep + json.dumps(batch)[1:-1]  # the list's items, as the whole list writes them
            sep = ", "
    yield '], "displayTimeUnit": "ms", "otherData": ' + json.dumps(_other_data(budget)) + "}"


def _event_batches(budget: FrameBudget) -> Iterator[list[dict]]:
    """The trace's events in order: the M events naming the process and thread, then each
    recorded frame's events (_frame_events)."""
    yield [
        {"ph": "M", "name": "process_name", "pid": PID, "tid": TID, "args": {"name": "quickjab"}},
        {"ph": "M", "name": "thread_name", "pid": PID, "tid": TID, "args": {"name": "main loop"}},
    ]
    frames = budget.frame_rows()
    if len(frames):
        yield from _frame_events(budget, frames, budget.span_rows())


def _other_data(budget: FrameBudget) -> dict:
    """The trace's otherData: the stages' budgets and overruns and the loop's totals."""
    stages = {s.name: {"budget_ms": s.budget_ms, "overruns": s.overruns} for s in budget.stages}
    return {
        "stages": stages,
        "frame_budget_ms": budget.frame_budget_ms,
        "frame_period_ms": budget.frame_period_ms,
        "dropped_steps": budget.dropped_steps,
        "frame_overruns": budget.frame_overruns,
        "frames_total": budget.frames,
    }


def _frame_events(budget: FrameBudget, frames: np.ndarray, spans: np.ndarray) -> Iterator[list[dict]]:
    """Per recorded frame (rows `frames`, at least one), once its spans have lengthened it: its
    X event, its spans' X events (rows `spans`) and its two C events, times from the first
    frame's start."""
    origin = int(budget.f_start[frames[0]])
    first_frame = budget.frames - len(frames)
    names = [s.name for s in budget.stages]
    limits_ns = [s.budget_ms * 1e6 if s.budget_ms else float("inf") for s in budget.stages]
    unaccounted_id = names.index(UNACCOUNTED)
    dropped_total = budget.dropped_steps - int(budget.f_dropped[frames].sum())
    # group spans by frame number once (rows are ordered by frame)
    span_frame = budget.s_frame[spans]
    bounds = np.searchsorted(span_frame, np.arange(first_frame, budget.frames + 1))
    for j, fr in enumerate(frames):
        start, end = int(budget.f_start[fr]), int(budget.f_end[fr])
        work = end - start - int(budget.f_wait[fr])
        ts, dur = _ts_dur(start - origin, end - origin)
        frame_event = {
            "ph": "X", "name": "frame", "cat": "frame", "pid": PID, "tid": TID,
            "ts": ts, "dur": dur,
            "args": {
                "frame": first_frame + j,
                "steps": int(budget.f_steps[fr]),
                "dropped": int(budget.f_dropped[fr]),
                "wait_us": _us(int(budget.f_wait[fr])),
                "unaccounted_us": 0.0,
                "overrun": work > budget.frame_period_ms * 1e6,
            },
        }
        events = [frame_event]
        rows = spans[bounds[j]: bounds[j + 1]]
        # in time order, the outer of two that start together first: a span is recorded when it
        # ends, so the ring holds it before the stage around it (ts went back on the thread)
        rows = rows[np.lexsort((budget.s_depth[rows], budget.s_start[rows]))]
        open_events = [frame_event]  # the frame, and the spans the next one may nest in, by depth
        for r in rows:
            stage = int(budget.s_stage[r])
            if stage == unaccounted_id:
                frame_event["args"]["unaccounted_us"] = _us(int(budget.s_dur[r]))
                continue
            span = _span_event(budget, r, names[stage], limits_ns[stage], origin)
            del open_events[span["args"]["depth"] + 1:]
            _enclose(open_events, span)
            open_events.append(span)
            events.append(span)
        dropped_total += int(budget.f_dropped[fr])
        events.append({
            "ph": "C", "name": "budget", "pid": PID, "tid": TID, "ts": _us(end - origin),
            "args": {"use_percent": 100.0 * work / (budget.frame_period_ms * 1e6)},
        })
        events.append({
            "ph": "C", "name": "dropped_steps", "pid": PID, "tid": TID, "ts": _us(end - origin),
            "args": {"dropped": dropped_total},
        })
        yield events


def _span_event(budget: FrameBudget, r: int, name: str, limit_ns: float, origin: int) -> dict:
    """The X event of span row `r`: a stage (depth 0, marked when over its budget `limit_ns`)
    or a span nested in one."""
    depth, dur = int(budget.s_depth[r]), int(budget.s_dur[r])
    args = {"step": int(budget.s_step[r]), "depth": depth}
    if depth == 0 and dur > limit_ns:
        args["overrun"] = True  # over the stage's declared budget: visible in Perfetto
    start = int(budget.s_start[r]) - origin
    ts, dur_us = _ts_dur(start, start + dur)
    return {
        "ph": "X", "name": name, "cat": "stage" if depth == 0 else "span",
        "pid": PID, "tid": TID, "ts": ts, "dur": dur_us, "args": args,
    }


def write_chrome_trace(budget: FrameBudget, path: str | os.PathLike) -> None:
    try:
        Path(path).parent.mkdir(parents=True, exist_ok=True)  # `--trace new/t.json`: made, as every output's folder
        # whole, or the previous trace as it was
        write_replacing(path, lambda f: f.writelines(text.encode("utf-8") for text in _trace_text(budget)))
    except OSError as exc:  # a full disk's ENOSPC names no file
        raise TraceError(f"{path}: cannot write the trace ({exc.strerror or exc})") from None


MAX_TRACE_BYTES = 256 * 2**20  # over an hour of play; parsed JSON takes ~10x its text
_MAX_COUNT = 10**9  # dropped steps in one frame: anything above is not a count
# A frame runs at most the loop's max_steps (5 by default); this leaves room for any loop set up
# otherwise and refuses what no loop runs (1e9 made "1000000299 steps")
_MAX_FRAME_STEPS = 1000
# a loop's step budget and frame period: 0.1 ms (10 kHz) to 10 s (0.1 Hz); 1e300 or 1e-300 printed
# 300-digit numbers and garbled the table's header. A stage budget is at most the same 10 s.
_PERIOD_MS = (0.1, 10_000.0)
_MAX_RUN_COUNT = 10**12  # otherData's totals of a run (frames, dropped steps, frames over period)
_FRAME_ARGS_NUMBERS = ("wait_us", "unaccounted_us")
_FRAME_ARGS_COUNTS = ("steps", "dropped")


def _number(x: object) -> bool:
    """A finite JSON number a float holds (bools are not numbers here; an integer of 400 digits
    is not one either: np.isfinite raised TypeError on it, float() OverflowError)."""
    if not isinstance(x, (int, float)) or isinstance(x, bool):
        return False
    try:
        return math.isfinite(x)
    except OverflowError:
        return False


def _bad_event(ev: object) -> str | None:
    """Why one trace event cannot be summarized, or None. Checks every field `quickjab
    profile` reads, so that the summary never meets a wrong type."""
    if not isinstance(ev, dict) or not isinstance(ev.get("ph"), str) or not isinstance(ev.get("name"), str):
        return "has no string 'ph' and 'name'"
    args = ev.get("args")
    if args is not None and not isinstance(args, dict):
        return "has args that are not an object"
    if ev["ph"] == "C" and ev["name"] == "dropped_steps":
        return _bad_dropped_counter(ev)
    if ev["ph"] != "X":
        return None
    ts, dur = ev.get("ts"), ev.get("dur")
    if not (_number(ts) and _number(dur) and dur >= 0 and abs(ts) < 1e15 and dur < 1e15):
        return f"({ev['name']!r}) needs finite numeric ts and dur >= 0"
    args = args or {}
    if "depth" in args and not (_number(args["depth"]) and args["depth"] >= 0):
        return f"({ev['name']!r}) has a depth that is not a count"
    if ev["name"] == "frame":
        for k in _FRAME_ARGS_NUMBERS:
            if k in args and not (_number(args[k]) and 0 <= args[k] < 1e15):
                return f"(frame) has args.{k} that is not a time"
        for k in _FRAME_ARGS_COUNTS:
            if k in args and not (_number(args[k]) and 0 <= args[k] <= _MAX_COUNT):
                return f"(frame) has args.{k} that is not a count"
        if "steps" in args and args["steps"] > _MAX_FRAME_STEPS:
            return f"(frame) has args.steps {args['steps']:.6g}, more than a loop runs in a frame ({_MAX_FRAME_STEPS})"
    return None


def _bad_dropped_counter(ev: dict) -> str | None:
    """The `dropped_steps` counter, which `quickjab profile` reads when frames do not say their
    dropped steps: a time and running totals that are counts."""
    if not (_number(ev.get("ts")) and abs(ev["ts"]) < 1e15):
        return "(dropped_steps) needs a finite numeric ts"
    if not all(_number(v) and 0 <= v <= _MAX_COUNT for v in (ev.get("args") or {}).values()):
        return "(dropped_steps) has a value that is not a count"
    return None


def _bad_other(other: object) -> str | None:
    """Why otherData cannot be used (budgets must be positive finite numbers), or None."""
    if not isinstance(other, dict):
        return "otherData is not an object"
    lo, hi = _PERIOD_MS
    for k in ("frame_budget_ms", "frame_period_ms"):
        if other.get(k) is not None and not (_number(other[k]) and other[k] > 0):
            return f"otherData.{k} is not a positive number of milliseconds"
        if other.get(k) is not None and not lo <= other[k] <= hi:
            return f"otherData.{k} {other[k]:.6g} is out of range: a loop's is {lo:g} to {hi:g} ms"
    for k in ("frames_total", "dropped_steps", "frame_overruns"):
        n = other.get(k)
        if n is not None and not (isinstance(n, int) and not isinstance(n, bool) and 0 <= n <= _MAX_RUN_COUNT):
            return f"otherData.{k} is not a count (0 to {_MAX_RUN_COUNT:.0e})"
    stages = other.get("stages")
    if stages is not None and not isinstance(stages, dict):
        return "otherData.stages is not an object"
    for name, v in (stages or {}).items():
        if isinstance(v, dict) and v.get("budget_ms") is not None and not (_number(v["budget_ms"]) and 0 <= v["budget_ms"] <= hi):
            return f"otherData.stages[{name!r}].budget_ms is not a number of milliseconds from 0 to {hi:g}"
    return None


def read_chrome_trace(path: str | os.PathLike) -> dict:
    """Load a trace (object or bare-array form) and check every field the profile relies on.
    Raises TraceError naming the file on anything else."""
    if os.fspath(path) == "":  # Path("") is ".": the error named the current folder
        raise TraceError("the trace path is empty")
    path = Path(path)
    try:
        st = os.stat(path)
        if not stat.S_ISREG(st.st_mode):
            raise TraceError(f"{path}: cannot read: not a regular file")
        if st.st_size > MAX_TRACE_BYTES:
            raise TraceError(f"{path}: {st.st_size / 2**20:.0f} MiB is over the {MAX_TRACE_BYTES // 2**20} MiB limit for a trace")
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise TraceError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise TraceError(f"{path}: cannot read: {exc}") from None
    except json.JSONDecodeError as exc:
        raise TraceError(f"{path}: not JSON (line {exc.lineno}: {exc.msg})") from None
    except RecursionError:
        raise TraceError(f"{path}: not a Chrome trace (nested too deeply)") from None
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        raise TraceError(f"{path}: not JSON ({exc})") from None
    if isinstance(data, list):
        data = {"traceEvents": data}
    if not isinstance(data, dict) or not isinstance(data.get("traceEvents"), list):
        raise TraceError(f"{path}: not a Chrome trace (no traceEvents list)")
    for i, ev in enumerate(data["traceEvents"]):
        why = _bad_event(ev)
        if why:
            raise TraceError(f"{path}: event {i} {why}")
    if not any(ev["ph"] == "X" and ev["name"] == "frame" for ev in data["traceEvents"]):
        if isinstance(data.get("otherData"), dict) and data["otherData"].get("frames_total") == 0:  # ours: a run cut short
            raise TraceError(f"{path}: no frames: the run ended before its first frame")
        raise TraceError(f"{path}: no 'frame' events (not written by a QuickJab loop?)")
    if data.get("otherData") is None:
        data["otherData"] = {}
    why = _bad_other(data["otherData"])
    if why:
        raise TraceError(f"{path}: {why}")
    return data
