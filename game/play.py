"""`quickjab play`: a boxing match against the Interaction Graph opponent.

Input: `--source URL` (serial://..., replay://..., wiimote-emu://..., keyboard://), by default
the first Wiimote found, else the keyboard with a banner saying so. `--demo` is the attract
mode: the virtual player boxes by itself. `--headless --frames N --screenshot out.png --trace
out.json` runs without a display (SDL dummy driver, virtual clock: reproducible with --seed)
and writes the last frame and the frame-budget trace.

Keys: Q W E R / U I O P punches and parries, Space block, arrows step; Esc pause, F3 frame
budget, F11 fullscreen. The Wiimote's Home button pauses too.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable

from engine import arguments
from engine.errors import InputError

DEFAULT_SOURCE = "wiimote://"
KEYBOARD_SOURCE = "keyboard://"
DEMO_SOURCE = "keyboard://?profile=experienced"
KEYBOARD_BANNER = "No Wiimote found: playing from the keyboard"
HEADLESS_FRAMES = 600  # `--headless` without `--frames` stops after 10 s of play, never runs on unseen
INVISIBLE_DRIVERS = ("offscreen", "dummy")  # SDL video drivers that open no window


def parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in arguments.window_size(text).lower().split("x"))
    except argparse.ArgumentTypeError as exc:  # one line naming --size, as before
        raise InputError(f"--size {text!r}: {exc}") from None
    return w, h


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("play", help="box: a match against the CPU, or two players with --players 2 (Wiimote, serial IMUs or the keyboard)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", default=None, help=f"source URL (default: {DEFAULT_SOURCE}, else {KEYBOARD_SOURCE})")
    p.add_argument("--demo", action="store_true", help="attract mode: a synthesized session from the virtual player")
    p.add_argument("--headless", action="store_true", help="no window: SDL dummy driver and a virtual clock (reproducible)")
    p.add_argument("--frames", type=arguments.positive_int, default=None,
                   help=f"stop after N rendered frames (default: until the window closes; {HEADLESS_FRAMES} with --headless)")
    p.add_argument("--screenshot", metavar="PNG", help="save the last frame to this PNG")
    p.add_argument("--trace", metavar="JSON", help="write the loop's Chrome trace here on exit")
    p.add_argument("--virtual-clock", action="store_true", help="a virtual clock in a real window: the same frames as --headless (tests)")
    p.add_argument("--seed", type=arguments.seed, default=0, help="seed for the virtual player and anything random (default 0)")
    p.add_argument("--size", default="1280x720", help="window size WxH (default 1280x720)")
    p.add_argument("--fullscreen", action="store_true", help="start fullscreen (F11 toggles)")
    p.add_argument("--low-power", action="store_true", help="render at 30 Hz on a half-size surface, flat shading, no antialiasing, fewer solver iterations (docs/performance.md)")
    p.add_argument("--templates", metavar="NPZ", help="recognition templates (default: yours from `quickjab train`, else the shipped set)")
    p.add_argument("--graph", metavar="NPZ", help="Interaction Graph table (default: the shipped one)")
    p.add_argument("--difficulty", choices=("easy", "normal", "hard", "adaptive"), default=None,
                   help="the CPU: how often it takes its best action, how late it reacts, its rest between moves, how "
                        "much its blows hurt; adaptive follows you to about half the rounds won (default normal; "
                        "D in the pause menu changes it)")
    p.add_argument("--left-handed", action="store_true", help="Wiimote in the left hand: mirror the templates (your own trained set is used as it is)")
    p.add_argument("--budget", action="store_true", help="show the frame-budget overlay from the start (F3 toggles)")
    p.add_argument("--no-sound", action="store_true", help="no sound")
    p.add_argument("--players", type=int, choices=(1, 2), default=1, help="2: a local match between two people, a controller each (game.two_player)")
    p.add_argument("--source2", default=None, help="player 2's source URL with --players 2 (default: the second Wiimote found, else the keyboard's right half)")
    p.add_argument("--profile", default=None, metavar="NAME", help="play with the templates `quickjab train --profile NAME` saved (default: your default set)")
    p.add_argument("--profile2", default=None, metavar="NAME", help="player 2's profile with --players 2")
    p.add_argument("--recognizer", action="append", default=[], metavar="NAME=VALUE",
                   help="a recognizer setting, e.g. noise_g=0.5 or main=auto (repeatable; docs/recognition.md lists them). "
                        "Over your config file's [recognizer] table ($XDG_CONFIG_HOME/quickjab/config.toml), over "
                        "the settings saved with the templates")
    p.set_defaults(func=run)


def check_visible_window(command: str) -> None:
    """A window was asked for but SDL fell back to a driver that shows nothing (no display: a
    server, an SSH session): say so and stop, rather than run unseen forever. Choosing such a
    driver on purpose (SDL_VIDEODRIVER=dummy) is allowed."""
    import pygame

    driver = pygame.display.get_driver()
    if driver in INVISIBLE_DRIVERS and os.environ.get("SDL_VIDEODRIVER", "").lower() != driver:
        raise InputError(f"no display: SDL opened its {driver!r} video driver, so no window would show; "
                         f"run it where a display is (DISPLAY / WAYLAND_DISPLAY), or use `quickjab {command} --headless --frames N`")


def headless_frames(frames: int | None, headless: bool, command: str) -> int | None:
    """The frame count to run: a headless run without --frames ends after HEADLESS_FRAMES."""
    if frames is None and headless:
        print(f"quickjab {command}: --headless without --frames: stopping after {HEADLESS_FRAMES} frames", file=sys.stderr)
        return HEADLESS_FRAMES
    return frames


def headless_env() -> None:
    """No window, no sound device: SDL's dummy drivers (set before pygame initialises)."""
    os.environ["SDL_VIDEODRIVER"] = "dummy"
    os.environ["SDL_AUDIODRIVER"] = "dummy"


def open_player_source(url: str | None, demo: bool, seed: int, clock) -> tuple[object, bool]:
    """The source to play with and whether the keyboard fallback was taken."""
    import game.keyboard_source  # noqa: F401 - registers keyboard://
    from engine.sensors import SourceError, SourceState, open_source

    if demo:
        return open_source(f"{DEMO_SOURCE}&seed={seed}", clock=clock), False
    if url is not None:
        if url.startswith("keyboard://") and "seed=" not in url:
            url += ("&" if "?" in url else "?") + f"seed={seed}"
        return open_source(url, clock=clock), False
    try:
        source = open_source(DEFAULT_SOURCE, clock=clock)
    except SourceError as exc:
        print(f"quickjab: {str(exc).split(';')[0]}; using the keyboard", file=sys.stderr)
    else:
        if source.state is not SourceState.DISCONNECTED:
            return source, False
        source.close()
    return open_source(f"{KEYBOARD_SOURCE}?seed={seed}", clock=clock), True


def run(args: argparse.Namespace) -> int:
    if getattr(args, "players", 1) == 2:
        from game.two_player import run_match

        return run_match(args)
    from game.user_config import recognizer_settings

    settings = recognizer_settings(getattr(args, "recognizer", None) or ())  # a bad file or value: before any window
    if getattr(args, "profile", None) is not None and args.templates is None:
        from game.two_player import seat_templates

        args.templates, note = seat_templates(args.profile, None)
        if note:
            print(f"quickjab play: {note}", file=sys.stderr)

    fallback = False

    def sources(clock) -> list:
        nonlocal fallback
        source, fallback = open_player_source(args.source, args.demo, args.seed, clock.seconds)
        if fallback:
            print(f"quickjab play: {KEYBOARD_BANNER}", file=sys.stderr)
        return [source]

    def session(sources: list, clock, size: tuple[int, int], surface_provider):
        from game.session import Session, SessionConfig

        config = SessionConfig(seed=args.seed, size=size, low_power=args.low_power, demo=args.demo,
                               keyboard_banner=fallback, templates=args.templates, graph=args.graph,
                               sound=not args.no_sound and not args.headless,
                               left_handed=args.left_handed, difficulty=args.difficulty or "normal",
                               recognizer=settings)
        return Session(sources[0], config, clock=clock, surface_provider=surface_provider)

    return run_session(args, "QuickJab", sources, session)


def run_session(args: argparse.Namespace, caption: str, open_sources: Callable[[object], list],
                make_session: Callable[..., object]) -> int:
    """What one- and two-player play share: the window (or none: --headless, which stops after
    HEADLESS_FRAMES without --frames), a clear error when SDL shows no window, the clock, the
    templates line, the loop, then the screenshot and trace, and the sources closed.
    `open_sources(clock)` returns the sources (opened before the window: a bad URL is an
    error, not a window that opens and closes); `make_session(sources, clock, size,
    surface_provider)` builds the session."""
    size = parse_size(args.size)
    if args.frames is not None and args.frames < 1:
        raise InputError("--frames must be at least 1")
    frames = headless_frames(args.frames, args.headless, "play")
    if args.headless:
        headless_env()
    import pygame

    from engine.clock import RealClock, VirtualClock
    from engine.trace import write_chrome_trace

    clock = VirtualClock() if args.headless or args.virtual_clock else RealClock()
    sources: list = []
    try:
        sources.extend(open_sources(clock))
        pygame.init()
        flags = pygame.RESIZABLE | (pygame.FULLSCREEN if args.fullscreen and not args.headless else 0)
        pygame.display.set_mode(size, flags)
        if not args.headless:
            check_visible_window("play")
        pygame.display.set_caption(caption)
        session = make_session(sources, clock, size, pygame.display.get_surface)
        for line in session.templates_lines():
            print(f"quickjab play: {line}", file=sys.stderr)
        session.hud_state.show_budget = args.budget
        session.on_toggle_fullscreen = pygame.display.toggle_fullscreen
        try:
            session.loop.run(frames=frames)
        finally:
            if args.screenshot:
                pygame.image.save(pygame.display.get_surface(), args.screenshot)
                print(f"quickjab play: wrote {args.screenshot}", file=sys.stderr)
            if args.trace:
                write_chrome_trace(session.loop.budget, args.trace)
                print(f"quickjab play: wrote {args.trace}", file=sys.stderr)
    finally:
        for source in sources:
            source.close()
        pygame.quit()
    return 0
