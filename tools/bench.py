"""`quickjab bench TARGET`: benchmarks that print figures and ratios against a peer measured
in the same run. Each target is a module with `add_arguments(parser)` and `run(args) -> int`."""

from __future__ import annotations

import argparse
import importlib

from engine.interrupt import ends_as_ctrl_c

# target name -> module; each is imported when the parser is built (for its arguments),
# so a target module imports what it measures (the recognizer, the physics, the Wiimote driver,
# the serial bridge, the game) inside run() and the functions run() calls, never at its top:
# `bench --help` and `bench startup` load none of it (tests/tools/test_startup.py)
TARGETS = {
    "loop": "tools.bench_loop",
    "synth": "tools.bench_synth",
    "physics": "tools.bench_physics",
    "wiimote": "tools.bench_wiimote",
    "graph": "tools.bench_graph",
    "recognition": "tools.bench_recognition",
    "serial": "tools.bench_serial",
    "frame": "tools.bench_frame",
    "startup": "tools.bench_startup",
}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="run a benchmark and print figures", description=__doc__)
    targets = p.add_subparsers(dest="target", metavar="TARGET", required=True)
    for name, module in TARGETS.items():
        mod = importlib.import_module(module)
        tp = targets.add_parser(name, help=summary(mod.__doc__), description=mod.__doc__)
        mod.add_arguments(tp)
        # SIGTERM and SIGHUP end a bench as Ctrl-C does (exit 130, no figures): SDL made SIGTERM a
        # quit event that `bench frame` took for the end of its match, and reported the cut run
        tp.set_defaults(func=ends_as_ctrl_c(mod.run))


def summary(doc: str | None) -> str:
    """A target's line in `bench --help`: its docstring's first paragraph, whole (its first line
    alone cut three of them mid-sentence: "..., all templates in one")."""
    return " ".join((doc or "").strip().split("\n\n")[0].split())
