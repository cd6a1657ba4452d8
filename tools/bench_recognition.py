"""Per-frame recognition cost: the incremental DTW (one new row per frame, all templates in one
numpy pass) against the peer measured in the same run, dtaidistance (C) recomputing the whole
buffer's DTW against every template from scratch each frame.

"x faster" compares the incremental DTW step (the method `auto` picks: "native" when the C
kernel can be built, else numpy, or "jit" from hundreds of templates) with the faster peer; a
last line says whether each target of issue 3 is met (<= 30 us and >= 10x at 13 templates, also
for the whole push; <= 0.6 ms and >= 30x at 1000), and of issue 14 for sizes written ACTIONSxK
(K templates per action): the whole push <= 40 us and >= 10x the peer at 13x3, <= 0.6 ms and
>= 30x at 1000x3 ("push x" is the peer over the whole push).
Templates are random smooth 6-D signals of 30-60 frames (punch-like lengths at 60 Hz); the
query is a 60-frame supplementary buffer. Reported: mean microseconds per frame over the
buffer, for the DTW step alone and for the whole DualBufferRecognizer.push (its templates rest on
1 g, as real ones do, so it runs their tilted copies too: 4x the templates in its DTW).
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable

import numpy as np

from engine import arguments
from engine.errors import InputError

# The recognizer's own limits, written out: importing them would load the recognizer whenever
# `bench` builds its parser (tools/bench.py); a test holds them equal.
MAX_FRAMES = 6000  # engine/recognition/config.py: its longest buffer (100 s)
MAX_TEMPLATES = 10_000  # engine/recognition/templates.py: the most a template file may hold
MAX_DIM = 60  # 20 sensors; the push's gravity and gate go per sensor of 3 values
# Issue 3's speed targets: templates -> (max us per frame, min x faster than the peer).
TARGETS = {13: (30.0, 10.0), 1000: (600.0, 30.0)}
# Issue 14's, for the whole push: (actions, templates per action) -> (max us, min x the peer).
PUSH_TARGETS = {(13, 3): (40.0, 10.0), (1000, 3): (600.0, 30.0)}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--sizes", default="13,1000,13x3,1000x3",
                   help="template counts, or ACTIONSxK for K templates per action (default 13,1000,13x3,1000x3)")
    p.add_argument("--dim", type=_dim, default=6, help=f"values per frame, 3 per sensor (default 6, at most {MAX_DIM})")
    p.add_argument("--buffer", type=arguments.int_range(1, MAX_FRAMES), default=60, help="query frames (default 60)")
    p.add_argument("--repeat", type=arguments.int_range(1, 1000), default=5, help="buffers timed per size (best kept)")
    p.add_argument("--sweep", action="store_true", help="also time scan vs loop (and jit) over many sizes")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def _dim(text: str) -> int:
    """An argparse type for --dim: 3 values per sensor, as the push takes them (0 or 4 was a
    traceback from the templates, a negative one from numpy)."""
    dim = arguments.int_range(3, MAX_DIM)(text)
    if dim % 3:
        raise argparse.ArgumentTypeError(f"{dim} is not a multiple of 3 (3 values per sensor)")
    return dim


_dim.__name__ = "integer"


def _signals(rng: np.random.Generator, n: int, dim: int, lo: int = 30, hi: int = 60) -> list[np.ndarray]:
    out = []
    for _ in range(n):
        length = int(rng.integers(lo, hi + 1))
        x = np.cumsum(rng.normal(0, 0.3, (length, dim)), axis=0)
        out.append(x)
    return out


def _time_frames(reset: Callable[[], object], push: Callable[[np.ndarray], object], query: np.ndarray,
                 repeat: int) -> float:
    """Best of `repeat` buffers: mean microseconds per `push` of a query frame after `reset`."""
    best = np.inf
    for _ in range(repeat):
        reset()
        t0 = time.perf_counter()
        for f in query:
            push(f)
        best = min(best, (time.perf_counter() - t0) / len(query))
    return best * 1e6


def _cell(value: float, width: int) -> str:
    """A figure of the table, or '-' where it was not measured (numpy at thousands of templates,
    numba or dtaidistance missing): it printed nan."""
    return f"{value:{width}.1f}" if value == value else f"{'-':>{width}}"


def _time_incremental(templates: list[np.ndarray], query: np.ndarray, method: str, repeat: int) -> float:
    from engine.recognition.dtw import IncrementalDTW

    dtw = IncrementalDTW(templates, method=method)
    return _time_frames(dtw.reset, dtw.push, query, repeat)


def _time_push(templates: list[np.ndarray], query: np.ndarray, repeat: int, per_action: int = 1) -> float:
    from engine.recognition import DualBufferRecognizer, Templates
    from engine.recognition.config import MAX_FRAMES

    actions = [f"a{k // per_action}" for k in range(len(templates))]
    gravity = np.tile([0.0, 0.0, 1.0], (len(templates), templates[0].shape[1] // 3))  # real templates rest on 1 g
    tm = Templates(actions, templates, gravity,
                   np.zeros(len(templates), dtype=int), np.full(len(templates), np.inf), feature="raw")
    rec = DualBufferRecognizer(tm, noise_g=0.0, null_frames=MAX_FRAMES)  # never ends a motion
    return _time_frames(rec.reset, rec.push, query, repeat)


def _time_peer(templates: list[np.ndarray], query: np.ndarray, repeat: int) -> tuple[float, str]:
    """dtaidistance recomputing the buffer against every template each frame; the faster of
    one C call per template and one blocked distance-matrix C call for all of them."""
    from dtaidistance import dtw_ndim

    tmpl = [np.ascontiguousarray(t, dtype=np.double) for t in templates]
    block = ((0, 1), (1, len(tmpl) + 1))

    def per_template(buf: np.ndarray) -> None:
        for t in tmpl:
            dtw_ndim.distance_fast(buf, t)

    def blocked(buf: np.ndarray) -> None:
        dtw_ndim.distance_matrix_fast([buf, *tmpl], block=block, compact=True, parallel=False)

    results = []
    # one C call per template is the slower way from a few dozen templates: skipped for many
    ways = (("per-template", per_template), ("matrix", blocked)) if len(tmpl) <= 100 else (("matrix", blocked),)
    for name, fn in ways:
        best = np.inf
        for _ in range(max(1, repeat // 2)):
            t0 = time.perf_counter()
            for i in range(1, len(query) + 1):
                fn(np.ascontiguousarray(query[:i], dtype=np.double))
            best = min(best, (time.perf_counter() - t0) / len(query))
        results.append((best * 1e6, name))
    fastest = min(results)
    return fastest[0], " ".join(f"{name} {us:.0f} us" for us, name in results) + f" (fastest: {fastest[1]})"


def _size(text: str) -> tuple[int, int]:
    """"13" -> (13 templates, 1 per action); "13x3" -> (39 templates, 3 per action); ValueError
    for no templates or more than a template file may hold."""
    actions, _, per = text.strip().partition("x")
    n, per_action = int(actions) * int(per or 1), int(per or 1)
    if int(actions) < 1 or per_action < 1 or n > MAX_TEMPLATES:  # 0 was a traceback from the templates
        raise ValueError(text)
    return n, per_action


def _measure(tm: list[np.ndarray], query: np.ndarray, repeat: int, per_action: int, jit: bool, native: bool) -> dict:
    """One size's figures (us per frame; nan where not measured) and the peer's description."""
    from engine.recognition.dtw import IncrementalDTW

    n = len(tm)
    times = {m: _time_incremental(tm, query, m, repeat) for m in ("scan", "loop")} if n <= 1000 else \
        {"scan": float("nan"), "loop": float("nan")}  # numpy at thousands: seconds, and never chosen
    times["jit"] = _time_incremental(tm, query, "jit", repeat) if jit else float("nan")
    times["native"] = _time_incremental(tm, query, "native", repeat) if native else float("nan")
    auto = IncrementalDTW(tm).method
    push = _time_push(tm, query, repeat, per_action)
    try:
        peer, how = _time_peer(tm, query, repeat)
    except ImportError:
        peer, how = float("nan"), "dtaidistance not installed"
    chosen = times[auto] if auto in times else _time_incremental(tm, query, auto, repeat)
    return {"times": times, "auto": auto, "chosen": chosen, "push": push, "peer": peer, "how": how,
            "ratio": peer / chosen, "push_ratio": peer / push}


def _targets(n: int, per_action: int, label: str, m: dict) -> tuple[str, dict[str, bool]] | None:
    """The issue targets this size has, as (its name in the targets line, {check: met}), or None."""
    if per_action == 1 and n in TARGETS:
        max_us, min_ratio = TARGETS[n]
        checks = {f"{m['auto']} <= {max_us:g} us": m["chosen"] <= max_us, f">= {min_ratio:g}x": m["ratio"] >= min_ratio}
        if n == 13:
            checks[f"push <= {max_us:g} us"] = m["push"] <= max_us
        return f"{n} templates", checks
    target = PUSH_TARGETS.get((n // per_action, per_action))
    if per_action > 1 and target:
        max_us, min_ratio = target
        return label, {f"push <= {max_us:g} us": m["push"] <= max_us, f"push >= {min_ratio:g}x": m["push_ratio"] >= min_ratio}
    return None


def _row(label: str, m: dict) -> str:
    t = m["times"]
    return (f"{label:>9} | {_cell(t['scan'], 8)} | {_cell(t['loop'], 8)} | {_cell(t['jit'], 8)} | {m['auto']:>6} | "
            f"{m['push']:8.1f} | {_cell(t['native'], 9)} | {_cell(m['peer'], 15)} | {_cell(m['ratio'], 8)} | "
            f"{_cell(m['push_ratio'], 6)} | {m['how']}")


def _figure(value: float) -> float | None:
    """A figure for --json: null where it was not measured (nan is not JSON)."""
    return None if value != value else round(value, 3)


def _json_size(label: str, n: int, per_action: int, m: dict) -> dict:
    return {"size": label, "templates": n, "per_action": per_action,
            **{f"{k}_us": _figure(v) for k, v in m["times"].items()}, "auto": m["auto"], "push_us": _figure(m["push"]),
            "peer_us": _figure(m["peer"]), "peer": m["how"], "speedup_vs_peer": _figure(m["ratio"]),
            "push_speedup_vs_peer": _figure(m["push_ratio"])}


def _sweep(rng: np.random.Generator, query: np.ndarray, dim: int, jit: bool, native: bool) -> dict[int, dict[str, float]]:
    methods = ("scan", "loop") + (("jit",) if jit else ()) + (("native",) if native else ())
    return {n: {m: _time_incremental(tm, query, m, 3) for m in methods}
            for n in (25, 50, 100, 200, 300, 500, 1000) for tm in [_signals(rng, n, dim)]}


def run(args: argparse.Namespace) -> int:
    from engine.recognition.dtw import jit_available, native_available

    rng = np.random.default_rng(0)
    try:
        sizes = [(_size(s), s.strip()) for s in args.sizes.split(",")]
    except ValueError:
        raise InputError(f"--sizes {args.sizes!r}: expected counts like 13,1000 or 13x3, "
                         f"from 1 to {MAX_TEMPLATES} templates each") from None
    query = np.cumsum(rng.normal(0, 0.3, (args.buffer, args.dim)), axis=0)
    jit, native = jit_available(), native_available()
    say = (lambda line: None) if args.json else print  # --json: the one JSON object is all of stdout
    say(f"per-frame cost, {args.dim}-D frames, {args.buffer}-frame buffer, templates of 30-60 frames")
    if not native:
        say("native: no C compiler (or QUICKJAB_NO_NATIVE / QUICKJAB_NO_JIT set): auto uses numpy, or jit for many templates")
    if not jit:
        say("jit: numba not importable (or QUICKJAB_NO_JIT=1)")
    say(f"{'templates':>9} | {'scan us':>8} | {'loop us':>8} | {'jit us':>8} | {'auto':>6} | {'push us':>8} | {'native us':>9} | {'dtaidistance us':>15} | {'x faster':>8} | {'push x':>6} | peer")
    fig: dict = {"dim": args.dim, "buffer_frames": args.buffer, "template_frames": [30, 60], "repeat": args.repeat,
                 "native_available": native, "jit_available": jit, "sizes": [], "targets": {}}
    verdicts = []
    for (n, per_action), label in sizes:
        m = _measure(_signals(rng, n, args.dim), query, args.repeat, per_action, jit, native)
        say(_row(label, m))
        fig["sizes"].append(_json_size(label, n, per_action, m))
        target = _targets(n, per_action, label, m)
        if target:
            name, checks = target
            fig["targets"][name] = checks
            verdicts.append(f"{name}: " + ", ".join(f"{check} {'yes' if ok else 'NO'}" for check, ok in checks.items()))
    if verdicts:
        say("targets: " + "; ".join(verdicts))
    if args.sweep:
        sweep = _sweep(rng, query, args.dim, jit, native)
        say("\n" + " vs ".join(next(iter(sweep.values()))) + " (us per frame)")
        for n, row in sweep.items():
            say(f"{n:>5}: " + "  ".join(f"{m} {us:8.1f}" for m, us in row.items()))
        fig["sweep_us"] = {str(n): {m: _figure(us) for m, us in row.items()} for n, row in sweep.items()}
    if args.json:
        print(json.dumps(fig, indent=2))
    return 0
