"""`quickjab soak [--steps 216000] [--minutes M] [--json]`: an hour of simulated play, headless.

The full Session (tools/scripted_match.py: the attract-mode player, synthesized by the virtual
player and recognized by the real recognizer, against the graph opponent; physics, hits,
match rules, HUD and renderer) on a VirtualClock, one match after another. The renderer draws
one frame per simulated second (`--render-every`) to a 1280x720 offscreen surface: enough to
exercise every drawing path and its caches for an hour without the wall time being all pixels.

Memory is sampled every `--sample-seconds` of simulated time: the process RSS
(/proc/self/statm) and the Python heap (sys.getallocatedblocks; tracemalloc's traced size too
with --tracemalloc, which slows the run down). Passes when no exception escaped, nothing was
dropped, and the RSS after warm-up never grew by more than `--max-growth-mb` (10 MB).
Prints recognizer events by kind, blows, knockdowns, rounds and matches.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import sys
import time
import traceback
from collections import Counter
from itertools import islice

from engine import arguments
from engine.clock import STEP_HZ
from engine.errors import InputError

HZ = STEP_HZ
HOUR_STEPS = 216_000
WARMUP_SECONDS = 60.0  # caches (text, static layers, hand motions, the graph) fill in the first minute


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("soak", help="an hour of simulated play headless: memory, events, no exception",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--steps", type=arguments.positive_int, default=None, help=f"60 Hz steps to play (default {HOUR_STEPS}: one hour)")
    p.add_argument("--minutes", type=arguments.positive_float, default=None, help="simulated minutes to play instead of --steps")
    p.add_argument("--seed", type=arguments.seed, default=0, help="seed of the scripted play (default 0)")
    p.add_argument("--render-every", type=arguments.non_negative_int, default=60, help="render one frame every N steps (default 60; 0: never)")
    p.add_argument("--sample-seconds", type=arguments.positive_float, default=10.0, help="simulated seconds between memory samples (default 10)")
    p.add_argument("--warmup-seconds", type=arguments.non_negative_float, default=WARMUP_SECONDS,
                   help=f"simulated seconds before the memory baseline (default {WARMUP_SECONDS:g})")
    p.add_argument("--max-growth-mb", type=arguments.positive_float, default=10.0, help="RSS growth after warm-up that fails the soak (default 10)")
    p.add_argument("--tracemalloc", action="store_true", help="also trace Python allocations (slower)")
    p.add_argument("--graph", metavar="NPZ", type=arguments.path_argument, help="Interaction Graph table (default: the shipped one)")
    p.add_argument("--templates", metavar="NPZ", type=arguments.path_argument, help="recognition templates (default: shipped, else synthesized)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(func=run)


def rss_bytes() -> int:
    """Resident set size from /proc/self/statm (0 where there is no /proc)."""
    try:
        with open("/proc/self/statm", encoding="ascii") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


class SoakCounters:
    """A stage after `match`: counts what happened this step and starts a new match when one
    ends (a soak is many matches)."""

    def __init__(self, session) -> None:
        self.s = session
        self.events: Counter[str] = Counter()
        self.blows = 0
        self.blocked = 0
        self.knockdowns = 0
        self.rounds = 0
        self.matches = 0
        self.results: Counter[str] = Counter()
        self._events_seen = 0
        self._blows_seen = 0
        self._round = session.match.round
        self._knockdowns = 0

    def __call__(self, step: int, dt: float) -> None:
        from game.match import Match

        s = self.s
        n = s.events_log.total  # every event appended (the log keeps only the recent ones)
        if n > self._events_seen:
            for ev in islice(reversed(s.events_log), n - self._events_seen):  # the new ones
                self.events[str(ev.get("event"))] += 1
            self._events_seen = n
        nb = s.blows_log.total
        if nb > self._blows_seen:
            for b in islice(reversed(s.blows_log), nb - self._blows_seen):
                self.blows += 1
                self.blocked += bool(b[3])
            self._blows_seen = nb
        m = s.match
        kd = sum(m.knockdowns)
        self.knockdowns += max(0, kd - self._knockdowns)
        self._knockdowns = kd
        if m.round != self._round:
            self.rounds += 1
            self._round = m.round
        if m.over:
            self.rounds += 1  # the last round of the match
            self.matches += 1
            self.results[str(m.result)] += 1
            s.match = Match()
            self._round, self._knockdowns = s.match.round, 0


def render_every(fn, n: int):
    """The session's render, run on one call in n (the loop still calls it every frame)."""
    calls = [0]

    def sometimes(alpha: float) -> None:
        calls[0] += 1
        if calls[0] % n == 1 or n == 1:
            fn(alpha)

    return sometimes


def soak(steps: int, seed: int = 0, render_n: int = 60, sample_seconds: float = 10.0,
         warmup_seconds: float = WARMUP_SECONDS, use_tracemalloc: bool = False,
         graph=None, templates=None, progress=None) -> dict:
    """Play `steps` steps; return the figures (see the module doc)."""
    import numpy as np

    from tools.scripted_match import build_session

    t_wall, t_cpu = time.perf_counter(), time.process_time()
    s = build_session(seed=seed, render=render_n > 0, size=(1280, 720), graph=graph, templates=templates)
    if render_n > 1:
        s.loop.wrap_stages(lambda name, fn: render_every(fn, render_n) if name.startswith("render") else fn)
    counters = SoakCounters(s)
    s.loop.add_stage("soak", counters, 0.0)
    sample_steps = max(1, int(round(sample_seconds * HZ)))
    warmup_steps = min(int(round(warmup_seconds * HZ)), steps)
    samples, error = _play_sampled(s, steps, sample_steps, use_tracemalloc, progress)
    wall, cpu = time.perf_counter() - t_wall, time.process_time() - t_cpu

    arr = np.array(samples, dtype=np.float64)
    memory = _memory_figures(arr, warmup_steps, use_tracemalloc)
    gc_counts = gc.get_stats()
    b = s.loop.budget
    mb = 1024 * 1024
    return {
        "steps": s.loop.step_index,
        "simulated_minutes": s.loop.step_index / HZ / 60,
        "wall_seconds": wall,
        "cpu_seconds": cpu,
        "steps_per_wall_second": s.loop.step_index / wall if wall > 0 else None,
        "exception": error,
        "dropped_steps": s.loop.dropped_steps,
        "frames": s.loop.frame_index,
        "stage_overruns": {st.name: st.overruns for st in b.stages if st.overruns},
        "recognizer_events": dict(counters.events),
        "recognizer_events_total": sum(counters.events.values()),
        "blows": counters.blows,
        "blocked": counters.blocked,
        "knockdowns": counters.knockdowns,
        "rounds": counters.rounds,
        "matches": counters.matches,
        "results": dict(counters.results),
        "memory": memory,
        "gc_collections": [g["collections"] for g in gc_counts],
        "memory_series": {"step": arr[:, 0].astype(int).tolist(), "rss_mb": (arr[:, 1] / mb).round(3).tolist()},
    }


def _play_sampled(s, steps: int, sample_steps: int, use_tracemalloc: bool,
                  progress) -> tuple[list[tuple[int, int, int, int]], str | None]:
    """Run the session to `steps`, sampling memory every `sample_steps`: the samples
    (step, rss, python blocks, traced bytes) and the exception's traceback, if one escaped."""
    import tracemalloc

    if use_tracemalloc:
        tracemalloc.start()
    samples: list[tuple[int, int, int, int]] = []

    def sample() -> None:
        traced = tracemalloc.get_traced_memory()[0] if use_tracemalloc else 0
        samples.append((s.loop.step_index, rss_bytes(), sys.getallocatedblocks(), traced))

    error = None
    try:
        sample()
        while s.loop.step_index < steps:
            s.loop.run(steps=min(sample_steps, steps - s.loop.step_index))
            sample()
            if progress is not None and len(samples) % 60 == 0:
                progress(s.loop.step_index, steps, samples[-1][1])
    except Exception:  # the soak's finding: report it, don't hide it
        error = traceback.format_exc()
    if use_tracemalloc:
        tracemalloc.stop()
    return samples, error


def _memory_figures(arr, warmup_steps: int, use_tracemalloc: bool) -> dict:
    """The memory figures from the samples (rows of step, rss, python blocks, traced bytes):
    where they stood at warm-up and how far they grew after it."""
    import numpy as np

    base_i = int(np.searchsorted(arr[:, 0], warmup_steps))
    base_i = min(base_i, len(arr) - 1)
    base, after = arr[base_i], arr[base_i:]
    mb = 1024 * 1024
    memory = {
        "rss_start_mb": arr[0, 1] / mb,
        "rss_at_warmup_mb": base[1] / mb,
        "rss_end_mb": arr[-1, 1] / mb,
        "rss_max_mb": arr[:, 1].max() / mb,
        "rss_growth_after_warmup_mb": float(after[:, 1].max() - base[1]) / mb,
        "rss_end_minus_warmup_mb": float(arr[-1, 1] - base[1]) / mb,
        "python_blocks_at_warmup": int(base[2]),
        "python_blocks_end": int(arr[-1, 2]),
        "python_blocks_growth_after_warmup": int(after[:, 2].max() - base[2]),
        "samples": len(arr),
        "warmup_seconds": warmup_steps / HZ,
    }
    if use_tracemalloc:
        memory["traced_at_warmup_mb"] = base[3] / mb
        memory["traced_growth_after_warmup_mb"] = float(after[:, 3].max() - base[3]) / mb
    return memory


def passed(fig: dict, max_growth_mb: float) -> bool:
    return (fig["exception"] is None and fig["dropped_steps"] == 0
            and fig["memory"]["rss_growth_after_warmup_mb"] < max_growth_mb)


def run(args: argparse.Namespace) -> int:
    if args.steps is not None and args.minutes is not None:
        raise InputError("give --steps or --minutes, not both")
    steps = HOUR_STEPS if args.steps is None and args.minutes is None else (
        args.steps if args.steps is not None else int(round(args.minutes * 60 * HZ)))
    if steps < 1:
        raise InputError(f"--steps/--minutes must give at least one step, got {steps}")
    if args.render_every < 0 or args.sample_seconds <= 0 or args.warmup_seconds < 0:
        raise InputError("--render-every >= 0, --sample-seconds > 0 and --warmup-seconds >= 0")
    # SDL turns SIGTERM into a quit event, which nothing in a soak reads (`kill` and `timeout` could
    # not stop it): leave SIGTERM to end the process (Ctrl-C is Python's own KeyboardInterrupt)
    os.environ.setdefault("SDL_NO_SIGNAL_HANDLERS", "1")

    def progress(step: int, total: int, rss: int) -> None:
        if not args.quiet:
            print(f"quickjab soak: {step}/{total} steps ({step / HZ / 60:.1f} min), RSS {rss / 2**20:.1f} MB",
                  file=sys.stderr, flush=True)

    fig = soak(steps, seed=args.seed, render_n=args.render_every, sample_seconds=args.sample_seconds,
               warmup_seconds=args.warmup_seconds, use_tracemalloc=args.tracemalloc, graph=args.graph,
               templates=args.templates, progress=progress)
    ok = passed(fig, args.max_growth_mb)
    fig["passed"] = ok
    if args.json:
        print(json.dumps(fig, indent=2))
    else:
        print(format_report(fig, args.max_growth_mb))
    return 0 if ok else 1


def format_report(fig: dict, max_growth_mb: float) -> str:
    m = fig["memory"]
    ev = ", ".join(f"{k} {v}" for k, v in sorted(fig["recognizer_events"].items()))
    lines = [
        f"soak: {fig['steps']} steps ({fig['simulated_minutes']:.1f} simulated minutes) in {fig['wall_seconds']:.0f} s wall "
        f"({fig['cpu_seconds']:.0f} s CPU, {fig['steps_per_wall_second']:.0f} steps/s), {fig['frames']} frames, "
        f"dropped {fig['dropped_steps']}",
        f"exception: {'none' if fig['exception'] is None else fig['exception'].strip().splitlines()[-1]}",
        f"recognizer events {fig['recognizer_events_total']} ({ev})",
        f"blows {fig['blows']} ({fig['blocked']} blocked), knockdowns {fig['knockdowns']}, rounds {fig['rounds']}, "
        f"matches {fig['matches']} {fig['results']}",
        f"RSS: start {m['rss_start_mb']:.1f} MB, after {m['warmup_seconds']:.0f} s warm-up {m['rss_at_warmup_mb']:.1f} MB, "
        f"end {m['rss_end_mb']:.1f} MB, max {m['rss_max_mb']:.1f} MB; growth after warm-up "
        f"{m['rss_growth_after_warmup_mb']:+.2f} MB (limit {max_growth_mb:g}), end - warm-up {m['rss_end_minus_warmup_mb']:+.2f} MB",
        f"Python heap blocks: {m['python_blocks_at_warmup']} after warm-up, {m['python_blocks_end']} at the end "
        f"(max growth {m['python_blocks_growth_after_warmup']:+d})"
        + (f"; traced {m['traced_at_warmup_mb']:.1f} MB, growth {m['traced_growth_after_warmup_mb']:+.2f} MB"
           if "traced_at_warmup_mb" in m else ""),
        f"stage overruns (wall clock, this machine): {fig['stage_overruns']}",
        f"{'PASS' if fig['passed'] else 'FAIL'}",
    ]
    if fig["exception"] is not None:
        lines.insert(2, fig["exception"])
    return "\n".join(lines)
