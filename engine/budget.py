"""Frame-budget accounting: stages declare a budget in ms, the loop times every stage of every
step and every render, and what the stages did not cover is booked as `unaccounted` so the
parts add up to wall time. Everything lives in preallocated numpy rings: recording a span
allocates nothing.

Per frame: stage spans (depth 0) + `wait` + `unaccounted` == the frame's wall time, exactly, in
integer ns. A stage overruns when one run of it exceeds its declared budget; a frame overruns
when its work (wall time minus waiting) exceeds the frame period (1000 / render_hz ms).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from engine.clock import STEP_MS

FRAME_BUDGET_MS = STEP_MS
WAIT = "wait"
UNACCOUNTED = "unaccounted"


@dataclass
class Stage:
    name: str
    budget_ms: float
    overruns: int = 0  # cumulative, not limited to the ring
    nested: bool = False  # a span inside a stage (`loop.span`), not a stage the loop runs


def percentiles_ms(durations_ns: np.ndarray) -> dict[str, float]:
    """p50, p95, p99 and max of durations in ns, as ms; zeros when empty."""
    if len(durations_ns) == 0:
        return {"p50": 0.0, "p95": 0.0, "p99": 0.0, "max": 0.0, "n": 0}
    ms = np.asarray(durations_ns, dtype=np.float64) / 1e6
    p50, p95, p99 = np.percentile(ms, [50, 95, 99])
    return {"p50": float(p50), "p95": float(p95), "p99": float(p99), "max": float(ms.max()), "n": int(len(ms))}


class FrameBudget:
    def __init__(self, capacity_frames: int = 3600, spans_per_frame: int = 48, frame_budget_ms: float = FRAME_BUDGET_MS):
        self.frame_budget_ms = frame_budget_ms  # one step's budget: the 16.7 ms line
        self.frame_period_ms = frame_budget_ms  # one rendered frame's slot; the loop sets it
        self.stages: list[Stage] = []
        self._index: dict[str, int] = {}
        self.capacity = capacity_frames
        n = capacity_frames
        self.f_start = np.zeros(n, np.int64)
        self.f_end = np.zeros(n, np.int64)
        self.f_steps = np.zeros(n, np.int32)
        self.f_dropped = np.zeros(n, np.int32)
        self.f_wait = np.zeros(n, np.int64)
        m = capacity_frames * spans_per_frame
        self.span_capacity = m
        self.s_stage = np.zeros(m, np.int16)
        self.s_frame = np.zeros(m, np.int64)
        self.s_step = np.zeros(m, np.int64)
        self.s_start = np.zeros(m, np.int64)
        self.s_dur = np.zeros(m, np.int64)
        self.s_depth = np.zeros(m, np.int8)
        self.frames = 0  # frames recorded in total
        self.spans = 0
        self.dropped_steps = 0
        self.frame_overruns = 0
        self.steps_per_frame: Counter[int] = Counter()
        self._frame_start = 0
        self._accounted = 0
        self.register(WAIT, 0.0)
        self.register(UNACCOUNTED, 0.0)

    # -- stages --------------------------------------------------------------------------
    def register(self, name: str, budget_ms: float) -> int:
        if name in self._index:
            stage = self.stages[self._index[name]]
            stage.budget_ms = budget_ms
            return self._index[name]
        self._index[name] = len(self.stages)
        self.stages.append(Stage(name, budget_ms))
        return self._index[name]

    def stage_id(self, name: str) -> int:
        """The id of `name`; a name not registered yet is a span's, and is registered as one."""
        if name in self._index:
            return self._index[name]
        sid = self.register(name, 0.0)
        self.stages[sid].nested = True
        return sid

    # -- recording -----------------------------------------------------------------------
    def begin_frame(self, start_ns: int) -> None:
        self._frame_start = start_ns
        self._accounted = 0

    def add_span(self, stage: int, step: int, start_ns: int, dur_ns: int, depth: int = 0) -> None:
        i = self.spans % self.span_capacity
        self.s_stage[i] = stage
        self.s_frame[i] = self.frames
        self.s_step[i] = step
        self.s_start[i] = start_ns
        self.s_dur[i] = dur_ns
        self.s_depth[i] = depth
        self.spans += 1
        if depth == 0:
            self._accounted += dur_ns
            st = self.stages[stage]
            if st.budget_ms and dur_ns > st.budget_ms * 1e6:
                st.overruns += 1

    def end_frame(self, end_ns: int, steps: int, dropped: int, wait_ns: int) -> None:
        wall = end_ns - self._frame_start
        self.add_span(self._index[WAIT], -1, end_ns - wait_ns, wait_ns)
        unaccounted = max(0, wall - self._accounted)
        self.add_span(self._index[UNACCOUNTED], -1, end_ns - wait_ns - unaccounted, unaccounted)
        i = self.frames % self.capacity
        self.f_start[i] = self._frame_start
        self.f_end[i] = end_ns
        self.f_steps[i] = steps
        self.f_dropped[i] = dropped
        self.f_wait[i] = wait_ns
        if wall - wait_ns > self.frame_period_ms * 1e6:
            self.frame_overruns += 1
        self.frames += 1
        self.dropped_steps += dropped
        self.steps_per_frame[steps] += 1

    # -- reading -------------------------------------------------------------------------
    def oldest_frame(self) -> int:
        """The oldest frame whose record and every span are still in the rings. When frames
        average more than `spans_per_frame` spans the span ring wraps first; frames that lost
        spans are left out rather than reported short."""
        oldest = self.frames - min(self.frames, self.capacity)
        if self.spans > self.span_capacity:
            first_kept = int(self.s_frame[self.spans % self.span_capacity])
            oldest = max(oldest, first_kept + 1)
        return min(oldest, self.frames)

    def frame_rows(self) -> np.ndarray:
        """Ring indices of the complete recorded frames, oldest first."""
        return np.arange(self.oldest_frame(), self.frames) % self.capacity

    def span_rows(self) -> np.ndarray:
        """Ring indices of the spans of those frames (and of the frame being recorded)."""
        n = min(self.spans, self.span_capacity)
        rows = np.arange(self.spans - n, self.spans) % self.span_capacity
        return rows[self.s_frame[rows] >= self.oldest_frame()]

    def stage_durations(self, name: str) -> np.ndarray:
        rows = self.span_rows()
        return self.s_dur[rows][self.s_stage[rows] == self._index[name]]

    def last_frame_ms(self) -> dict[str, float]:
        """Per stage, ms spent in the most recent frame (for the on-screen overlay)."""
        out = {s.name: 0.0 for s in self.stages}
        if not self.frames:
            return out
        rows = self.span_rows()
        rows = rows[(self.s_frame[rows] == self.frames - 1) & (self.s_depth[rows] == 0)]
        for r in rows:
            out[self.stages[self.s_stage[r]].name] += self.s_dur[r] / 1e6
        return out

    def summary(self) -> dict:
        rows = self.frame_rows()
        work = (self.f_end[rows] - self.f_start[rows]) - self.f_wait[rows]
        stages = {}
        for st in self.stages:
            pct = percentiles_ms(self.stage_durations(st.name))
            stages[st.name] = {
                **pct,
                "budget_ms": st.budget_ms,
                "share_p50": pct["p50"] / self.frame_budget_ms,
                "share_p99": pct["p99"] / self.frame_budget_ms,
                "overruns": st.overruns,
            }
        return {
            "frames": self.frames,
            "steps": int(sum(k * v for k, v in self.steps_per_frame.items())),
            "dropped_steps": self.dropped_steps,
            "frame_overruns": self.frame_overruns,
            "frame_budget_ms": self.frame_budget_ms,
            "frame_period_ms": self.frame_period_ms,
            "frame_work": percentiles_ms(work),
            "frame_wall": percentiles_ms(self.f_end[rows] - self.f_start[rows]),
            "steps_per_frame": {str(k): v for k, v in sorted(self.steps_per_frame.items())},
            "stages": stages,
        }
