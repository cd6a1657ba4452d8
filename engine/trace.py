"""Export a FrameBudget to the Chrome Trace Event Format (FORMATS.md), and read one back.

One `frame` X event per rendered frame; inside it one X event per stage per step, the render
stage (its name starts with `render`), `wait` and `unaccounted`; spans inside a stage nest in
it. C events carry the frame's budget use and the dropped-step count; M events name the
process and thread. Times are microseconds from the first recorded frame.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from engine.budget import FrameBudget

PID, TID = 1, 1


def chrome_trace(budget: FrameBudget) -> dict:
    frames = budget.frame_rows()
    spans = budget.span_rows()
    events: list[dict] = [
        {"ph": "M", "name": "process_name", "pid": PID, "tid": TID, "args": {"name": "quickjab"}},
        {"ph": "M", "name": "thread_name", "pid": PID, "tid": TID, "args": {"name": "main loop"}},
    ]
    if len(frames) == 0:
        return {"traceEvents": events, "displayTimeUnit": "ms", "otherData": {"stages": {}}}
    origin = int(budget.f_start[frames[0]])
    first_frame = budget.frames - len(frames)
    names = [s.name for s in budget.stages]
    dropped_total = budget.dropped_steps - int(budget.f_dropped[frames].sum())
    # group spans by frame number once (rows are ordered by frame)
    span_frame = budget.s_frame[spans]
    bounds = np.searchsorted(span_frame, np.arange(first_frame, budget.frames + 1))
    for j, fr in enumerate(frames):
        start, end = int(budget.f_start[fr]), int(budget.f_end[fr])
        work = end - start - int(budget.f_wait[fr])
        events.append({
            "ph": "X", "name": "frame", "cat": "frame", "pid": PID, "tid": TID,
            "ts": (start - origin) / 1000, "dur": (end - start) / 1000,
            "args": {"frame": first_frame + j, "steps": int(budget.f_steps[fr])},
        })
        for r in spans[bounds[j]: bounds[j + 1]]:
            events.append({
                "ph": "X", "name": names[budget.s_stage[r]], "cat": "stage", "pid": PID, "tid": TID,
                "ts": (int(budget.s_start[r]) - origin) / 1000, "dur": int(budget.s_dur[r]) / 1000,
                "args": {"step": int(budget.s_step[r]), "depth": int(budget.s_depth[r])},
            })
        dropped_total += int(budget.f_dropped[fr])
        events.append({
            "ph": "C", "name": "budget", "pid": PID, "tid": TID, "ts": (end - origin) / 1000,
            "args": {"use_percent": 100.0 * work / (budget.frame_budget_ms * 1e6)},
        })
        events.append({
            "ph": "C", "name": "dropped_steps", "pid": PID, "tid": TID, "ts": (end - origin) / 1000,
            "args": {"dropped": dropped_total},
        })
    stages = {s.name: {"budget_ms": s.budget_ms, "overruns": s.overruns} for s in budget.stages}
    return {
        "traceEvents": events,
        "displayTimeUnit": "ms",
        "otherData": {"stages": stages, "frame_budget_ms": budget.frame_budget_ms, "dropped_steps": budget.dropped_steps},
    }


def write_chrome_trace(budget: FrameBudget, path: str | os.PathLike) -> None:
    Path(path).write_text(json.dumps(chrome_trace(budget)), encoding="utf-8")
