"""The single-threaded fixed-timestep loop, after Glenn Fiedler's "Fix Your Timestep!".

Time is an integer accumulator in units of ns x hz, so one step is exactly 1e9 units and a
60 Hz step never drifts by rounding. Each rendered frame: read the clock, add the frame time
(clamped at 0.25 s), run at most `max_steps` due steps (the rest are counted as dropped,
never carried: no spiral of death), render with the interpolation alpha, then wait for the
absolute deadline of the next frame. Deadlines are absolute (anchor + k periods, so waiting
never accumulates drift) and reset to a fresh anchor after a stall (so a hitch is not
followed by a burst of zero-wait frames); a wait never ends before the next step is due (so a
frame after a late wake-up does not render again with no step run).

Stages receive the step index and dt; none reads a clock. Every stage and the render are
timed with perf_counter_ns into a FrameBudget. See docs/engine.md.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from engine.budget import FrameBudget
from engine.clock import NS_PER_S, STEP_HZ, RealClock, VirtualClock

StageFn = Callable[[int, float], None]
RenderFn = Callable[[float], None]

MAX_FRAME_NS = 250_000_000  # frame time clamp: a longer pause costs dropped steps, not a spiral
MAX_STEPS_PER_FRAME = 5


class FixedStepLoop:
    """Runs registered stages at a fixed `hz` and one render per frame at `render_hz`.

    `auto_freeze_gc=True` calls `gc.freeze()` once, when `run` first starts (everything the caller
    loaded before that moves to the permanent generation and is never walked again).
    """

    def __init__(
        self,
        clock: RealClock | VirtualClock | None = None,
        hz: int = STEP_HZ,
        render_hz: int | None = None,
        max_steps: int = MAX_STEPS_PER_FRAME,
        budget: FrameBudget | None = None,
        auto_freeze_gc: bool = True,
    ):
        self.clock = clock or RealClock()
        self.hz = hz
        self.dt = 1.0 / hz
        self.render_hz = render_hz or hz
        if self.render_hz > hz:
            raise ValueError("render_hz cannot exceed the step rate")
        self.max_steps = max_steps
        self.budget = budget or FrameBudget(frame_budget_ms=1000.0 / hz)
        self.budget.frame_period_ms = 1000.0 / self.render_hz
        self.auto_freeze_gc = auto_freeze_gc
        self.gc_frozen = False
        self._stages: list[tuple[int, StageFn]] = []
        self._render: tuple[int, RenderFn] | None = None
        self.step_index = 0  # steps run so far; the next step's index
        self.frame_index = 0
        self.dropped_steps = 0
        self.alpha = 0.0
        self.running = False
        self.last_lateness_ns = 0  # how late the last wait returned after its deadline
        self.stalls = 0  # times the deadline schedule was reset after a stall
        self._acc = 0  # ns * hz
        self._last_ns: int | None = None
        self._anchor_ns = 0
        self._deadline_k = 0
        self._depth = 0
        self._span_step = 0  # the step of the stage running now: what its spans are booked to
        self._in_stages = False  # a stage or the render is running: spans are timed

    # -- set-up ---------------------------------------------------------------------------
    def add_stage(self, name: str, fn: StageFn, budget_ms: float) -> None:
        """Run fn(step, dt) every step, in registration order, within budget_ms."""
        self._stages.append((self.budget.register(name, budget_ms), fn))

    def set_render(self, fn: RenderFn, budget_ms: float, name: str = "render") -> None:
        """Run fn(alpha) once per rendered frame. The name must start with 'render'."""
        if not name.startswith("render"):
            raise ValueError("the render stage's name starts with 'render' (docs/formats.md)")
        self._render = (self.budget.register(name, budget_ms), fn)

    def wrap_stages(self, wrap: Callable[[str, Callable], Callable]) -> None:
        """Replace each stage's fn (and the render's) by wrap(name, fn): for benchmarks that
        add their own timers around the stages; the loop's budget keeps timing the wrapped."""
        names = {sid: s.name for sid, s in enumerate(self.budget.stages)}
        self._stages = [(sid, wrap(names[sid], fn)) for sid, fn in self._stages]
        if self._render is not None:
            sid, fn = self._render
            self._render = (sid, wrap(names[sid], fn))

    def step_time(self, step: int) -> float:
        """The simulation instant of a step in seconds, k / hz exactly (never k * dt summed)."""
        return step / self.hz

    @staticmethod
    def freeze_gc() -> None:
        """Collect once, then freeze: the collector stops walking what is loaded so far."""
        gc.collect()
        gc.freeze()

    @contextmanager
    def span(self, name: str) -> Iterator[None]:
        """Time a part of a stage; it nests inside the stage (or span) around it in the trace.
        Outside the loop's stages (a draw before `run`, an `until` callback) it times nothing: the
        trace has no stage, nor frame, to put it in."""
        if not self._in_stages:
            yield
            return
        start = time.perf_counter_ns()
        self._depth += 1
        try:
            yield
        finally:
            self._depth -= 1
            self.budget.add_span(
                self.budget.stage_id(name), self._span_step, start,
                time.perf_counter_ns() - start, self._depth + 1,
            )

    # -- running --------------------------------------------------------------------------
    def _frame_period_ns(self, k: int) -> int:
        # rounded up, so that k frames always hold at least k * hz / render_hz whole steps
        return -((-k * NS_PER_S) // self.render_hz)

    def run_frame(self, limit: int | None = None) -> int:
        """One rendered frame: due steps (at most `limit`), render, wait. Returns the number
        of steps run. Steps held back by `limit` stay owed; they are not dropped, and the
        frame does not wait for its deadline: the next frame reads the same clock and runs them
        first, as this frame would have (so `run(steps=...)` split into calls of any size runs
        every step at the same clock reading; see docs/engine.md)."""
        now = self.clock.now_ns()
        perf = time.perf_counter_ns
        frame_start = perf()
        budget = self.budget
        budget.begin_frame(frame_start)
        if self._last_ns is None:
            self._last_ns = now
            self._anchor_ns = now
            self._deadline_k = 0
            # the first frame runs one step so that there is a state to render
            self._acc = NS_PER_S
        raw = now - self._last_ns
        self._last_ns = now
        clamped = min(raw, MAX_FRAME_NS)
        self._acc += clamped * self.hz
        due = self._acc // NS_PER_S
        allowed = min(due, self.max_steps)
        run = allowed if limit is None else min(allowed, limit)
        self._acc -= (due - (allowed - run)) * NS_PER_S
        # what could not run, plus the whole steps the clamp cut off, is dropped, never carried;
        # the cut-off's fraction of a step is owed like any other (it was lost: run + dropped fell
        # short of the time passed by up to a step per hitch)
        cut = (raw - clamped) * self.hz
        dropped = (due - allowed) + cut // NS_PER_S
        self._acc += cut % NS_PER_S
        self.dropped_steps += dropped
        self._in_stages = True
        try:
            for _ in range(run):
                step, dt = self.step_index, self.dt
                self._span_step = step
                for sid, fn in self._stages:
                    t0 = perf()
                    fn(step, dt)
                    budget.add_span(sid, step, t0, perf() - t0)
                self.step_index += 1
            self.alpha = min(self._acc, NS_PER_S) / NS_PER_S
            if self._render is not None:
                sid, fn = self._render
                self._span_step = self.step_index - 1
                t0 = perf()
                fn(self.alpha)
                budget.add_span(sid, self.step_index - 1, t0, perf() - t0)  # the last step it drew
        finally:
            self._in_stages = False
        wait_start = perf()
        if run == allowed:  # else held back by `limit`: the next frame is this one's rest
            self._wait_next_deadline()
        end = perf()
        budget.end_frame(end, run, dropped, end - wait_start)
        self.frame_index += 1
        return run

    def _next_step_due_ns(self) -> int:
        # the instant the accumulator holds a whole step again: a frame woken before it would
        # find no step to run and render the same state again
        return self._last_ns + -(-(NS_PER_S - self._acc) // self.hz)

    def _wait_next_deadline(self) -> None:
        self._deadline_k += 1
        deadline = self._anchor_ns + self._frame_period_ns(self._deadline_k)
        now = self.clock.now_ns()
        due = self._next_step_due_ns()
        if now > deadline + self._frame_period_ns(1):
            # stalled: start a fresh schedule. If steps are owed already (the stall was inside
            # this frame) the next frame is an immediate catch-up frame; if this frame was the
            # catch-up (its wait before it returned late) the schedule starts at the next step's
            # due time, so no frame renders with nothing run
            self._anchor_ns, self._deadline_k = max(now, due), 0
            self.stalls += 1
            if due <= now:
                self.last_lateness_ns = now - deadline
                return
            target = due
        else:
            # a frame that ran late already caught up the steps of the deadline just missed:
            # skip to the first deadline of the schedule at which a step is due again
            while deadline < due:  # at most a step and a period on: a few turns
                self._deadline_k += 1
                deadline = self._anchor_ns + self._frame_period_ns(self._deadline_k)
            target = deadline
        self.clock.wait_until(target)
        self.last_lateness_ns = self.clock.now_ns() - target

    def run(
        self,
        steps: int | None = None,
        frames: int | None = None,
        until: Callable[[], bool] | None = None,
    ) -> None:
        """Run until `steps` steps (exactly: the last frame runs no more than are left) or
        `frames` frames have run, `until()` is true, or stop()."""
        if self.auto_freeze_gc and not self.gc_frozen:
            self.freeze_gc()
            self.gc_frozen = True
        self.running = True
        start_steps, start_frames = self.step_index, self.frame_index
        while self.running:
            if steps is not None and self.step_index - start_steps >= steps:
                break
            if frames is not None and self.frame_index - start_frames >= frames:
                break
            if until is not None and until():
                break
            self.run_frame(None if steps is None else steps - (self.step_index - start_steps))
        self.running = False

    def stop(self) -> None:
        self.running = False

    def resync(self) -> None:
        """Forget the time since the last frame (after a pause menu, a load screen): the next
        frame runs no catch-up steps and drops none, and deadlines start again from now."""
        if self._last_ns is not None:
            now = self.clock.now_ns()
            self._last_ns, self._anchor_ns, self._deadline_k = now, now, 0
