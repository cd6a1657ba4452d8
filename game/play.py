"""`quickjab play`: a boxing match against the Interaction Graph opponent.

Input: `--source URL` (serial://..., replay://..., wiimote-emu://..., keyboard://), by default
the first Wiimote found, else the keyboard with a banner saying so. `--demo` is the attract
mode: the virtual player boxes by itself. `--headless --frames N --screenshot out.png --trace
out.json` runs without a display (SDL dummy driver, virtual clock: reproducible with --seed; a live
serial:// or wiimote:// device runs on the real clock)
and writes the last frame and the frame-budget trace.

Keys: Q W E R / U I O P punches and parries, Space block, arrows step; Esc pause, F3 frame
budget, F11 fullscreen. The Wiimote's Home button pauses too.
"""

from __future__ import annotations

import argparse
import sys

from engine import arguments

# the start-up pieces play shares with two_player and training; re-exported for the callers of
# game.play's names
from game.launch import (
    DEFAULT_SOURCE,
    HEADLESS_FRAMES,
    KEYBOARD_SOURCE,
    open_player_source,
    run_session,
    wants_sound,
)
from game.launch import DEMO_SOURCE as DEMO_SOURCE
from game.launch import INVISIBLE_DRIVERS as INVISIBLE_DRIVERS
from game.launch import check_visible_window as check_visible_window
from game.launch import headless_env as headless_env
from game.launch import headless_frames as headless_frames
from game.launch import parse_size as parse_size


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("play", help="box: a match against the CPU, or two players with --players 2 (Wiimote, serial IMUs or the keyboard)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", default=None, help=f"source URL (default: {DEFAULT_SOURCE}, else {KEYBOARD_SOURCE})")
    p.add_argument("--demo", action="store_true", help="attract mode: a synthesized session from the virtual player")
    p.add_argument("--headless", action="store_true", help="no window: SDL dummy driver and a virtual clock (reproducible; a live serial:// or wiimote:// device runs on the real clock)")
    p.add_argument("--frames", type=arguments.positive_int, default=None,
                   help=f"stop after N rendered frames (default: until the window closes; {HEADLESS_FRAMES} with --headless)")
    p.add_argument("--screenshot", type=arguments.image_file, metavar="PNG", help="save the last frame to this PNG")
    p.add_argument("--trace", type=arguments.trace_file, metavar="JSON", help="write the loop's Chrome trace here on exit")
    p.add_argument("--virtual-clock", action="store_true", help="a virtual clock in a real window: the same frames as --headless with a simulated source (tests; a live device too)")
    p.add_argument("--seed", type=arguments.seed, default=0, help="seed for the virtual player and anything random (default 0)")
    p.add_argument("--size", default="1280x720", help="window size WxH (default 1280x720; under 640x360 the text is hard to read)")
    p.add_argument("--fullscreen", action="store_true", help="start fullscreen (F11 toggles)")
    p.add_argument("--low-power", action="store_true", help="render at 30 Hz on a half-size surface, flat shading, no antialiasing, fewer solver iterations (docs/performance.md)")
    p.add_argument("--templates", metavar="NPZ", type=arguments.path_argument, help="recognition templates (default: yours from `quickjab train`, else the shipped set)")
    p.add_argument("--graph", metavar="NPZ", type=arguments.path_argument, help="Interaction Graph table (default: the shipped one)")
    p.add_argument("--difficulty", choices=("easy", "normal", "hard", "adaptive"), default=None,
                   help="the CPU: how often it takes its best action, how late it reacts, its rest between moves, how "
                        "much its blows hurt; adaptive follows you to about half the rounds won (default normal; "
                        "D in the pause menu changes it)")
    p.add_argument("--left-handed", action="store_true", help="Wiimote in the left hand: mirror the templates (your own trained set is used as it is)")
    p.add_argument("--budget", action="store_true", help="show the frame-budget overlay from the start (F3 toggles)")
    p.add_argument("--no-sound", action="store_true", help="no sound")
    p.add_argument("--players", type=int, choices=(1, 2), default=1, help="2: a local match between two people, a controller each (game.two_player)")
    p.add_argument("--source2", default=None, help="player 2's source URL with --players 2 (default: the second Wiimote found, else the keyboard: its right half when player 1 plays from it too)")
    p.add_argument("--profile", default=None, metavar="NAME", help="play with the templates `quickjab train --profile NAME` saved (default: your default set)")
    p.add_argument("--profile2", default=None, metavar="NAME", help="player 2's profile with --players 2")
    p.add_argument("--recognizer", action="append", default=[], metavar="NAME=VALUE",
                   help="a recognizer setting, e.g. noise_g=0.5 or main=auto (repeatable; docs/recognition.md lists them). "
                        "Over your config file's [recognizer] table ($XDG_CONFIG_HOME/quickjab/config.toml), over "
                        "the settings saved with the templates")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if getattr(args, "players", 1) == 2:
        from game.two_player import run_match

        return run_match(args)
    player2 = [opt for opt, value in (("--source2", getattr(args, "source2", None)),
                                      ("--profile2", getattr(args, "profile2", None))) if value is not None]
    if player2:  # as two players' note on the CPU's options: said, not silently dropped
        print(f"quickjab play: {' and '.join(player2)} ignored without --players 2: they are player 2's", file=sys.stderr)
    if getattr(args, "profile", None) is not None and args.templates is not None:
        print("quickjab play: --profile ignored with --templates: --templates names the set", file=sys.stderr)
    from game.user_config import recognizer_settings

    settings = recognizer_settings(getattr(args, "recognizer", None) or ())  # a bad file or value: before any window
    if getattr(args, "profile", None) is not None and args.templates is None:
        from game.two_player import seat_templates

        args.templates, note = seat_templates(args.profile, None)
        if note:
            print(f"quickjab play: {note}", file=sys.stderr)

    fallback = ""  # why the keyboard stands in for a Wiimote

    def sources(clock) -> list:
        nonlocal fallback
        source, fallback = open_player_source(args.source, args.demo, args.seed, clock.seconds)
        if fallback:
            print(f"quickjab play: {fallback}: playing from the keyboard", file=sys.stderr)
        from engine.recording import say_notes

        say_notes(source.file_notes, "play")  # a replayed recording's row left out (a cut last row)
        return [source]

    def session(sources: list, clock, size: tuple[int, int], surface_provider):
        from game.session import Session, SessionConfig

        config = SessionConfig(seed=args.seed, size=size, low_power=args.low_power, demo=args.demo,
                               keyboard_banner=bool(fallback), templates=args.templates, graph=args.graph,
                               sound=wants_sound(args),
                               left_handed=args.left_handed, difficulty=args.difficulty or "normal",
                               recognizer=settings)
        return Session(sources[0], config, clock=clock, surface_provider=surface_provider)

    return run_session(args, "QuickJab", sources, session)
