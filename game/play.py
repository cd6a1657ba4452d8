"""`quickjab play`: until the boxing game lands, this starts the sensor scope.

It opens `--source` (default: the first Wiimote, `wiimote://`); when no Wiimote can be
opened it falls back to the synthetic `demo://` source and says so in a banner.
"""

from __future__ import annotations

import argparse
import sys

from engine.clock import RealClock, VirtualClock

DEFAULT_SOURCE = "wiimote://"
FALLBACK_SOURCE = "demo://"


def register(sub: argparse._SubParsersAction) -> None:
    from tools.scope import add_view_arguments  # the scope stands in for the game for now

    p = sub.add_parser("play", help="play (for now: the sensor scope on the Wiimote, or the demo source)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", default=DEFAULT_SOURCE, help=f"source URL (default {DEFAULT_SOURCE}, falling back to {FALLBACK_SOURCE})")
    add_view_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tools.scope import headless_env, open_with_fallback, run_scope, view_from_args

    view = view_from_args(args)
    if args.headless:
        headless_env()
    clock: RealClock | VirtualClock = VirtualClock() if args.headless else RealClock()
    source, banner = open_with_fallback(args.source, clock.seconds, DEFAULT_SOURCE, FALLBACK_SOURCE)
    if banner:
        print(banner, file=sys.stderr)
    run_scope(source, clock=clock, frames=args.frames, screenshot=args.screenshot, trace=args.trace,
              banner=banner, view=view)
    return 0
