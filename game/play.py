"""`quickjab play`: until the boxing game lands, this starts the sensor scope.

It opens `--source` (default: the first Wiimote, `wiimote://`); when no Wiimote can be
opened it falls back to the synthetic `demo://` source and says so in a banner.
"""

from __future__ import annotations

import argparse
import sys

from engine.clock import RealClock, VirtualClock
from engine.sensors import Source, SourceError, SourceState, open_source
from engine.sensors.source import Clock

DEFAULT_SOURCE = "wiimote://"
FALLBACK_SOURCE = "demo://"


def open_with_fallback(url: str, clock: Clock) -> tuple[Source, str]:
    """Open `url`; if it is the default Wiimote and none can be opened, open the demo source.
    Returns (source, banner); the banner is empty unless the fallback was taken."""
    try:
        source = open_source(url, clock=clock)
    except SourceError as exc:
        if url != DEFAULT_SOURCE:
            raise
        reason = str(exc)
    else:
        if source.state is not SourceState.DISCONNECTED or url != DEFAULT_SOURCE:
            return source, ""
        reason = "no Wiimote found"
        source.close()
    print(f"quickjab play: no Wiimote: {reason}", file=sys.stderr)
    banner = "No Wiimote found: showing the synthetic demo source. Pair one, or pass --source URL."
    return open_source(FALLBACK_SOURCE, clock=clock), banner


def register(sub: argparse._SubParsersAction) -> None:
    from tools.scope import add_view_arguments  # the scope stands in for the game for now

    p = sub.add_parser("play", help="play (for now: the sensor scope on the Wiimote, or the demo source)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", default=DEFAULT_SOURCE, help=f"source URL (default {DEFAULT_SOURCE}, falling back to {FALLBACK_SOURCE})")
    add_view_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tools.scope import headless_env, run_scope, view_from_args

    view = view_from_args(args)
    if args.headless:
        headless_env()
    clock: RealClock | VirtualClock = VirtualClock() if args.headless else RealClock()
    source, banner = open_with_fallback(args.source, clock.seconds)
    if banner:
        print(banner, file=sys.stderr)
    run_scope(source, clock=clock, frames=args.frames, screenshot=args.screenshot, trace=args.trace,
              banner=banner, view=view)
    return 0
