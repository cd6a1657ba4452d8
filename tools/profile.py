"""`quickjab profile TRACE.json [--plot out.png] [--json]`: the frame-budget summary of a Chrome
trace written by the loop (engine/trace.py): per stage p50/p95/p99/max in ms, the p99 as a
share of the 16.7 ms step budget, overruns; per frame the work time, overruns, dropped steps
and the steps-per-frame histogram. `--plot` draws the frame-time histogram and stacked
per-stage bars per frame against the 16.7 ms line.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections import Counter

import numpy as np

from engine import arguments
from engine.budget import UNACCOUNTED, WAIT, percentiles_ms
from engine.clock import STEP_MS
from engine.errors import InputError, refuse_overwriting
from engine.trace import read_chrome_trace

DEFAULT_BUDGET_MS = STEP_MS
MAX_PLOT_STAGES = 16  # bands in the stacked plot: each is a fill and a legend entry (2000 took 10 s)


def profile_summary(trace: dict) -> dict:
    """The summary of a trace read by read_chrome_trace, as plain data."""
    other = trace.get("otherData") or {}
    budget_ms = float(other.get("frame_budget_ms") or DEFAULT_BUDGET_MS)
    period_ms = float(other.get("frame_period_ms") or budget_ms)
    declared = {k: float(v.get("budget_ms") or 0.0) for k, v in (other.get("stages") or {}).items() if isinstance(v, dict)}
    xs = [e for e in trace["traceEvents"] if e["ph"] == "X"]
    frames = sorted((e for e in xs if e["name"] == "frame"), key=lambda e: e["ts"])
    f_ts = np.array([e["ts"] for e in frames], dtype=np.float64)
    f_dur = np.array([e["dur"] for e in frames], dtype=np.float64)
    f_args = [e.get("args") or {} for e in frames]
    wait_us = np.array([float(a.get("wait_us", 0.0)) for a in f_args])
    unacc_us = np.array([float(a.get("unaccounted_us", 0.0)) for a in f_args])
    own = all("steps" in a for a in f_args) and all("depth" in (e.get("args") or {}) for e in xs if e["name"] != "frame")
    # this project's traces say it in their args; another writer's are read from their times
    timed_steps, timed_nested = ([0] * len(frames), set()) if own else _by_time(xs, frames)
    steps = [int(a["steps"]) if "steps" in a else n for a, n in zip(f_args, timed_steps, strict=True)]
    dropped = int(sum(int(a.get("dropped", 0)) for a in f_args)) if any("dropped" in a for a in f_args) \
        else _counter_total(trace["traceEvents"], "dropped_steps")
    work_us = f_dur - wait_us

    durations: dict[str, list[float]] = {}
    nested: set[str] = set()
    for e in xs:
        if e["name"] == "frame":
            continue
        durations.setdefault(e["name"], []).append(float(e["dur"]))
        args = e.get("args") or {}
        if args.get("depth", 0) if "depth" in args else id(e) in timed_nested:
            nested.add(e["name"])
    if any("unaccounted_us" in a for a in f_args):  # this project's arg: another writer's is not known, not 0
        durations.setdefault(UNACCOUNTED, []).extend(unacc_us.tolist())

    stages = {}
    for name, d in durations.items():
        d_ns = np.asarray(d) * 1000.0
        pct = percentiles_ms(d_ns)
        b = declared.get(name, 0.0)
        stages[name] = {
            **pct,
            "budget_ms": b,
            "share_p99": pct["p99"] / budget_ms,
            "overruns": int(np.sum(d_ns > b * 1e6)) if b > 0 else None,
            "nested": name in nested,
        }
    return {
        "frames": len(frames),
        **_run_totals(other, len(frames)),
        "steps": int(sum(steps)),
        "dropped_steps": dropped,
        "frame_budget_ms": budget_ms,
        "frame_period_ms": period_ms,
        "frame_work": percentiles_ms(work_us * 1000.0),
        "frame_overruns": int(np.sum(work_us > period_ms * 1000.0)),
        "steps_per_frame": {str(k): v for k, v in sorted(Counter(steps).items())},
        "stages": stages,
        "_frame_ts": f_ts,  # for the plot, with the frame events in time order; dropped before printing
        "_frames": frames,
    }


def _frames_total(other: dict, held: int) -> int:
    """The run's frames, otherData.frames_total: more than the `held` frames in the trace when
    the loop's ring kept only the last ones (read_chrome_trace refuses one that is not a count)."""
    total = other.get("frames_total")
    if isinstance(total, int) and not isinstance(total, bool) and 0 <= total <= 10**12:
        return max(total, held)
    return held


def _run_totals(other: dict, held: int) -> dict:
    """The whole run's frames, dropped steps and frames over period (otherData), which the F3
    overlay shows: more than the `held` frames' when the loop's ring kept only the last ones."""
    return {"frames_total": _frames_total(other, held), "run_dropped_steps": _run_count(other, "dropped_steps"),
            "run_frame_overruns": _run_count(other, "frame_overruns")}


def _run_count(other: dict, key: str) -> int | None:
    """otherData's count `key` for the whole run, or None when missing or not a count."""
    n = other.get(key)
    if isinstance(n, int) and not isinstance(n, bool) and 0 <= n <= 10**12:
        return n
    return None


def _whole_run(s: dict, held: int, key: str) -> str:
    """The text " (N in the whole run)" when the trace holds only the last frames and the run's count differs."""
    n = s.get(key)
    if s.get("frames_total", s["frames"]) <= s["frames"] or n is None or n == held:
        return ""
    return f" ({n} in the whole run)"


def _by_time(xs: list[dict], frames: list[dict]) -> tuple[list[int], set[int]]:
    """What docs/formats.md alone says of a trace, for one from another writer (this project's
    own carry `steps`, `dropped` and `depth` in their args): each frame's steps, the most events
    of one stage directly inside it (the render stage aside: one a frame), and the ids of the
    events nested inside a stage; both from the events' times on their thread."""
    index = {id(f): k for k, f in enumerate(frames)}
    counts: list[Counter] = [Counter() for _ in frames]
    nested: set[int] = set()
    stack: list[dict] = []
    # outer first; of two events with the same times the `frame` is the outer one
    for e in sorted(xs, key=lambda e: (str(e.get("pid")), str(e.get("tid")), e["ts"], -e["dur"], e["name"] != "frame")):
        while stack and (stack[-1].get("pid"), stack[-1].get("tid")) != (e.get("pid"), e.get("tid")):
            stack.pop()
        while stack and stack[-1]["ts"] + stack[-1]["dur"] < e["ts"] + e["dur"]:
            stack.pop()  # ended before this one does: not around it
        inside = [o for o in stack if o["name"] != "frame"]
        if e["name"] != "frame":
            if inside:
                nested.add(id(e))
            elif stack and stack[-1]["name"] == "frame" and not e["name"].startswith("render"):
                counts[index[id(stack[-1])]][e["name"]] += 1
        stack.append(e)
    return [max(c.values(), default=0) for c in counts], nested


def _counter_total(events: list[dict], name: str) -> int:
    """The last value of a `C` counter (a running total, as docs/formats.md's dropped steps)."""
    counter = sorted((e for e in events if e.get("ph") == "C" and e.get("name") == name), key=lambda e: e.get("ts", 0))
    values = [v for e in counter for v in (e.get("args") or {}).values() if isinstance(v, (int, float))]
    return int(values[-1]) if values else 0


def format_table(s: dict) -> str:
    b = s["frame_budget_ms"]
    total = s.get("frames_total", s["frames"])
    held = f" (the last of {total} run)" if total > s["frames"] else ""
    lines = [
        f"{s['frames']} frames{held}, {s['steps']} steps, {s['dropped_steps']} dropped steps"
        f"{_whole_run(s, s['dropped_steps'], 'run_dropped_steps')}; "
        f"step budget {b:.1f} ms, frame period {s['frame_period_ms']:.1f} ms",
        "",
        f"{'stage':<22}{'n':>7}{'p50 ms':>9}{'p95 ms':>9}{'p99 ms':>9}{'max ms':>9}{f'p99/{b:.1f}ms':>11}{'budget':>8}{'overruns':>9}",
    ]
    order = sorted(s["stages"], key=lambda k: (k in (WAIT, UNACCOUNTED), k == WAIT, k.startswith("render"), s["stages"][k]["nested"]))
    for name in order:
        st = s["stages"][name]
        label = ("  " + name) if st["nested"] else name
        budget = f"{st['budget_ms']:.2f}" if st["budget_ms"] else "-"
        over = "-" if st["overruns"] is None else str(st["overruns"])
        lines.append(
            f"{label[:21]:<22}{st['n']:>7}{st['p50']:>9.3f}{st['p95']:>9.3f}{st['p99']:>9.3f}{st['max']:>9.3f}"
            f"{100 * st['share_p99']:>10.1f}%{budget:>8}{over:>9}"
        )
    w = s["frame_work"]
    lines += [
        "",
        f"frame work (wall minus wait): p50 {w['p50']:.3f}  p95 {w['p95']:.3f}  p99 {w['p99']:.3f}  max {w['max']:.3f} ms; "
        f"{s['frame_overruns']} frames over {s['frame_period_ms']:.1f} ms{_whole_run(s, s['frame_overruns'], 'run_frame_overruns')}",
        "steps per frame: " + ", ".join(f"{k}: {v}" for k, v in s["steps_per_frame"].items()),
    ]
    return "\n".join(lines)


def _below_outliers(values: np.ndarray) -> float:
    """The largest value once the top 0.5 % (at least one: the start-up frame) is set aside."""
    if len(values) < 2:
        return float(values.max()) if len(values) else 0.0
    k = max(1, len(values) // 200)
    return float(np.sort(values)[-k - 1])


def save_figure(fig, path: str, dpi: float) -> None:
    """fig.savefig, then closed; a file it cannot write (a full disk: ENOSPC names no file) is
    an InputError naming it."""
    import matplotlib.pyplot as plt

    try:
        os.makedirs(os.path.dirname(path) or ".", exist_ok=True)  # `--plot new/p.png`: made, as every output's folder
        fig.savefig(path, dpi=dpi)
    except OSError as exc:
        raise InputError(f"{path}: cannot write the plot ({exc.strerror or exc})") from None
    except RuntimeError as exc:  # a format whose tool is missing (.pgf without LaTeX)
        said = str(exc).strip().splitlines() or [exc.__class__.__name__]
        raise InputError(f"{path}: matplotlib cannot write the plot: {said[0]}") from None
    finally:
        plt.close(fig)


def _largest_stages(per_frame: dict[str, np.ndarray], most: int) -> tuple[list[str], dict[str, np.ndarray]]:
    """At most `most` bands: the stages of the largest total time, then the rest summed as one
    ("N other stages"); all of them, in their order, when there are no more."""
    names = list(per_frame)
    if len(names) <= most:
        return names, per_frame
    order = sorted(names, key=lambda n: -float(per_frame[n].sum()))
    kept, rest = order[: most - 1], order[most - 1 :]
    other = f"{len(rest)} other stages"
    return [*kept, other], {**{n: per_frame[n] for n in kept}, other: np.sum([per_frame[n] for n in rest], axis=0)}


def plot_profile(trace: dict, summary: dict, out: str, max_bars: int = 600) -> dict:
    """Frame-time histogram and stacked per-stage bars (the last `max_bars` frames). A frame's
    work is drawn against the frame period (16.7 ms, 33.3 ms in low power). Both axes end a
    little above the 99.5th percentile (and the period): a start-up frame of 300 ms would flatten
    everything else; the frames beyond are counted in the title. Returns the axis limits."""
    try:
        import matplotlib
    except ImportError:
        raise InputError("--plot needs matplotlib (pip install 'quickjab[dev]')") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    budget = summary["frame_budget_ms"]
    f_ts, frames = summary["_frame_ts"], summary["_frames"]
    work = np.array([(e["dur"] - (e.get("args") or {}).get("wait_us", 0.0)) / 1000 for e in frames])
    names = [n for n in summary["stages"] if n != WAIT and not summary["stages"][n]["nested"]]
    per_frame = {n: np.zeros(len(frames)) for n in names}
    for e in trace["traceEvents"]:
        if e["ph"] != "X" or e["name"] not in per_frame or (e.get("args") or {}).get("depth", 0):
            continue
        i = int(np.searchsorted(f_ts, e["ts"], side="right")) - 1
        if 0 <= i < len(frames):
            per_frame[e["name"]][i] += e["dur"] / 1000
    if UNACCOUNTED in per_frame:
        per_frame[UNACCOUNTED] = np.array([(e.get("args") or {}).get("unaccounted_us", 0.0) / 1000 for e in frames])
    names, per_frame = _largest_stages(per_frame, MAX_PLOT_STAGES)

    period = float(summary.get("frame_period_ms") or budget)
    top = max(1.25 * period, 1.15 * _below_outliers(work))
    beyond = int(np.sum(work > top))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 4.8), gridspec_kw={"width_ratios": [1, 2]})
    ax1.hist(np.minimum(work, top), bins=np.linspace(0, top, 61), color="#4c72b0")
    ax1.axvline(period, color="#c44e52", linestyle="--", label=f"{period:.1f} ms frame period")
    ax1.set_xlim(0, top)
    ax1.set_xlabel("frame work time (ms)")
    ax1.set_ylabel("frames")
    ax1.set_title("frame time histogram" + (f" ({beyond} frames over {top:.0f} ms in the last bin, max {work.max():.0f} ms)" if beyond else ""),
                  fontsize=10)
    ax1.legend()
    sl = slice(max(0, len(frames) - max_bars), len(frames))
    x = np.arange(sl.start, sl.stop)
    bottom = np.zeros(len(x))
    for n in names:  # stacked bars, one per frame, drawn as stepped areas (fast for many frames)
        vals = per_frame[n][sl]
        ax2.fill_between(x, bottom, bottom + vals, step="mid", label=n, linewidth=0)
        bottom = bottom + vals
    ax2.axhline(period, color="#c44e52", linestyle="--", label=f"{period:.1f} ms frame period")
    stacked_top = max(1.25 * period, 1.15 * _below_outliers(bottom))
    ax2.set_ylim(0, stacked_top)
    over = int(np.sum(bottom > stacked_top))
    ax2.set_xlabel("frame")
    ax2.set_ylabel("ms")
    ax2.set_title("per-stage time per frame (stacked)" + (f"; {over} frames above the axis" if over else ""), fontsize=10)
    ax2.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)  # beside the bars, not over them
    fig.tight_layout()
    save_figure(fig, out, 100)
    return {"hist_xmax": top, "bars_ymax": stacked_top, "period_ms": period, "stages": names}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("profile", help="summarize a frame-budget Chrome trace (table, --plot, --json)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("trace", metavar="TRACE.json", type=arguments.path_argument, help="a Chrome trace written by the loop (e.g. `quickjab scope --trace`)")
    p.add_argument("--plot", type=arguments.plot_file, metavar="PNG", help="draw the frame-time histogram and stacked per-stage bars here")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    refuse_overwriting({"--plot": args.plot}, [args.trace])
    trace = read_chrome_trace(args.trace)
    summary = profile_summary(trace)
    if args.plot:
        plot_profile(trace, summary, args.plot)  # args.plot is the file written (a .png added to none)
        print(f"quickjab profile: wrote {args.plot}", file=sys.stderr)  # stderr: --json's stdout stays JSON
    public = {k: v for k, v in summary.items() if not k.startswith("_")}
    print(json.dumps(public, indent=2) if args.json else format_table(public))
    return 0
