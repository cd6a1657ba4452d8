"""Export a FrameBudget to the Chrome Trace Event Format (FORMATS.md), and read one back.

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
import os
from pathlib import Path

import numpy as np

from engine.budget import UNACCOUNTED, FrameBudget
from engine.errors import InputError

PID, TID = 1, 1


class TraceError(InputError):
    """A trace file that cannot be read as a QuickJab Chrome trace; names the file."""


def _us(ns: int) -> float:
    return ns / 1000


def chrome_trace(budget: FrameBudget) -> dict:
    frames = budget.frame_rows()
    spans = budget.span_rows()
    events: list[dict] = [
        {"ph": "M", "name": "process_name", "pid": PID, "tid": TID, "args": {"name": "quickjab"}},
        {"ph": "M", "name": "thread_name", "pid": PID, "tid": TID, "args": {"name": "main loop"}},
    ]
    stages = {s.name: {"budget_ms": s.budget_ms, "overruns": s.overruns} for s in budget.stages}
    other = {
        "stages": stages,
        "frame_budget_ms": budget.frame_budget_ms,
        "frame_period_ms": budget.frame_period_ms,
        "dropped_steps": budget.dropped_steps,
        "frame_overruns": budget.frame_overruns,
        "frames_total": budget.frames,
    }
    if len(frames) == 0:
        return {"traceEvents": events, "displayTimeUnit": "ms", "otherData": other}
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
        frame_event = {
            "ph": "X", "name": "frame", "cat": "frame", "pid": PID, "tid": TID,
            "ts": _us(start - origin), "dur": _us(end - start),
            "args": {
                "frame": first_frame + j,
                "steps": int(budget.f_steps[fr]),
                "dropped": int(budget.f_dropped[fr]),
                "wait_us": _us(int(budget.f_wait[fr])),
                "unaccounted_us": 0.0,
                "overrun": work > budget.frame_period_ms * 1e6,
            },
        }
        events.append(frame_event)
        for r in spans[bounds[j]: bounds[j + 1]]:
            stage = int(budget.s_stage[r])
            if stage == unaccounted_id:
                frame_event["args"]["unaccounted_us"] = _us(int(budget.s_dur[r]))
                continue
            depth, dur = int(budget.s_depth[r]), int(budget.s_dur[r])
            args = {"step": int(budget.s_step[r]), "depth": depth}
            if depth == 0 and dur > limits_ns[stage]:
                args["overrun"] = True  # over the stage's declared budget: visible in Perfetto
            events.append({
                "ph": "X", "name": names[stage], "cat": "stage" if depth == 0 else "span",
                "pid": PID, "tid": TID,
                "ts": _us(int(budget.s_start[r]) - origin), "dur": _us(dur), "args": args,
            })
        dropped_total += int(budget.f_dropped[fr])
        events.append({
            "ph": "C", "name": "budget", "pid": PID, "tid": TID, "ts": _us(end - origin),
            "args": {"use_percent": 100.0 * work / (budget.frame_period_ms * 1e6)},
        })
        events.append({
            "ph": "C", "name": "dropped_steps", "pid": PID, "tid": TID, "ts": _us(end - origin),
            "args": {"dropped": dropped_total},
        })
    return {"traceEvents": events, "displayTimeUnit": "ms", "otherData": other}


def write_chrome_trace(budget: FrameBudget, path: str | os.PathLike) -> None:
    Path(path).write_text(json.dumps(chrome_trace(budget)), encoding="utf-8")


def read_chrome_trace(path: str | os.PathLike) -> dict:
    """Load a trace (object or bare-array form) and check the keys the profile relies on.
    Raises TraceError naming the file on anything else."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise TraceError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise TraceError(f"{path}: cannot read: {exc}") from None
    except json.JSONDecodeError as exc:
        raise TraceError(f"{path}: not JSON (line {exc.lineno}: {exc.msg})") from None
    if isinstance(data, list):
        data = {"traceEvents": data}
    if not isinstance(data, dict) or not isinstance(data.get("traceEvents"), list):
        raise TraceError(f"{path}: not a Chrome trace (no traceEvents list)")
    for i, ev in enumerate(data["traceEvents"]):
        if not isinstance(ev, dict) or "ph" not in ev or "name" not in ev:
            raise TraceError(f"{path}: event {i} has no 'ph' or 'name'")
        if ev["ph"] == "X":
            ts, dur = ev.get("ts"), ev.get("dur")
            if not isinstance(ts, (int, float)) or not isinstance(dur, (int, float)) or dur < 0:
                raise TraceError(f"{path}: event {i} ({ev['name']!r}) needs numeric ts and dur >= 0")
    if not any(ev["ph"] == "X" and ev["name"] == "frame" for ev in data["traceEvents"]):
        raise TraceError(f"{path}: no 'frame' events (not written by a QuickJab loop?)")
    data.setdefault("otherData", {})
    return data
