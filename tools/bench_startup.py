"""Start-up: wall time and peak memory of `quickjab play --demo --headless --frames 1` (load
everything, box one frame, quit) against its peer measured in the same run, a bare
`python -c "import numpy, pygame"` (what any pygame game pays before its own code).

Each run starts a fresh interpreter; play and peer alternate so both see the same machine
load. Reported: min and median over the runs of the wall time and of the child's peak RSS
(its VmHWM from /proc at exit: rusage's maxrss would carry the forking parent's peak across
exec), the ratio play / peer, and issue 14's targets (wall <= 3x the peer's, peak RSS <= 120 MB). One untimed play run first builds what is built once per machine (the
C kernels, Python's bytecode cache when it is on), and it prints whether those run native or numpy.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from engine import arguments
from engine.errors import InputError

REPO = Path(__file__).resolve().parents[1]
MAX_RATIO = 3.0
MAX_RSS_MB = 120.0
PLAY = ["play", "--demo", "--headless", "--frames", "1"]
MARK = "STARTUP-PEAK-KB "
# Each child reports its own peak resident memory when it exits, on stderr.
REPORT = (f"\ndef _peak():\n    for line in open('/proc/self/status'):\n        if line.startswith('VmHWM:'):\n"
          f"            import sys; sys.stderr.write('{MARK}' + line.split()[1] + '\\n')\n")
PLAY_CODE = REPORT + f"import sys\nsys.argv = ['quickjab', *{PLAY!r}]\nfrom tools.cli import main\ntry:\n    code = main()\nfinally:\n    _peak()\nsys.exit(code)\n"
PEER_CODE = REPORT + "import numpy, pygame\n_peak()\n"


def kernel_report() -> tuple[str, dict]:
    """Whether the C kernels (engine/native.py) run native or numpy here, and why: one line,
    and per kernel. Loads them in this process (the children share its cache and environment)."""
    from engine import native
    from engine.physics import collision, constraints
    from engine.recognition import dtw_native

    collision.kernels()
    constraints.project_kernel()
    dtw_native.push_row_native()
    stems = ("contacts", "stick_project", "dtw_push_row")
    return native.describe(stems), {k: v for k, v in native.status().items() if k in stems}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--runs", type=arguments.int_range(1, 1000), default=5, help="runs of each (default 5; at most 1000)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")


def run_once(code: str) -> tuple[float, float]:
    """(wall seconds, peak RSS MB) of one fresh interpreter running `code`."""
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy",
           "PYTHONPATH": os.pathsep.join([str(REPO), *filter(None, [os.environ.get("PYTHONPATH")])])}
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env, stdout=subprocess.DEVNULL,
                       stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    peak = [line[len(MARK):] for line in r.stderr.splitlines() if line.startswith(MARK)]
    if r.returncode != 0 or not peak:
        raise InputError(f"the start-up run failed (exit {r.returncode}): {r.stderr.strip().splitlines()[-1:]}")
    return wall, int(peak[-1]) / 1024.0


def run(args: argparse.Namespace) -> int:
    run_once(PLAY_CODE)  # warm-up: one-time builds and caches, not start-up
    kernels, per_kernel = kernel_report()
    play, peer = [], []
    for _ in range(args.runs):
        play.append(run_once(PLAY_CODE))
        peer.append(run_once(PEER_CODE))

    def summary(runs: list[tuple[float, float]]) -> dict:
        walls, rss = [w for w, _ in runs], [r for _, r in runs]
        return {"wall_min_s": min(walls), "wall_median_s": statistics.median(walls),
                "rss_min_mb": min(rss), "rss_median_mb": statistics.median(rss), "rss_max_mb": max(rss)}

    p, q = summary(play), summary(peer)
    ratio_min, ratio_median = p["wall_min_s"] / q["wall_min_s"], p["wall_median_s"] / q["wall_median_s"]
    result = {"runs": args.runs, "play": p, "import_numpy_pygame": q,
              "ratio_min": ratio_min, "ratio_median": ratio_median,
              "kernels": per_kernel,
              "bytecode_cache": not sys.dont_write_bytecode and not os.environ.get("PYTHONDONTWRITEBYTECODE"),
              "targets": {"ratio_median_le_3": ratio_median <= MAX_RATIO, "rss_le_120mb": p["rss_max_mb"] <= MAX_RSS_MB}}
    if args.json:
        import json

        print(json.dumps(result, indent=2))
        return 0
    print(f"start-up, {args.runs} runs each, fresh interpreters, alternating (quickjab {' '.join(PLAY)})")
    print(kernels)
    if not result["bytecode_cache"]:
        print("note: PYTHONDONTWRITEBYTECODE is set: every run compiles the game's sources (an install would not)")
    print(f"{'':28} | {'wall min s':>10} | {'wall median s':>13} | {'peak RSS MB (min / median / max)':>32}")
    for name, s in (("quickjab play ... --frames 1", p), ("import numpy, pygame", q)):
        print(f"{name:28} | {s['wall_min_s']:10.3f} | {s['wall_median_s']:13.3f} | "
              f"{s['rss_min_mb']:9.1f} / {s['rss_median_mb']:6.1f} / {s['rss_max_mb']:6.1f}")
    print(f"play / import: {ratio_min:.2f}x (min), {ratio_median:.2f}x (median)")
    print(f"targets: wall <= {MAX_RATIO:g}x the import (median) {'yes' if result['targets']['ratio_median_le_3'] else 'NO'}; "
          f"peak RSS <= {MAX_RSS_MB:g} MB (every run) {'yes' if result['targets']['rss_le_120mb'] else 'NO'}")
    return 0
