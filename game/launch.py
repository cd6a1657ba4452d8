"""What the game's windowed commands share to start (`quickjab play`, one or two players, and
`quickjab train`): the window size, the headless mode and its frame count, the check that a
window shows, the player's source with its keyboard fallback, and the run of a session's loop.
game.play and game.two_player both build on it, so neither imports the other for these.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, TypeVar

from engine import arguments
from engine.errors import InputError, refuse_overwriting

if TYPE_CHECKING:
    from engine.budget import FrameBudget
    from game.session import Session

T = TypeVar("T")
DEFAULT_SOURCE = "wiimote://"
KEYBOARD_SOURCE = "keyboard://"
DEMO_SOURCE = "keyboard://?profile=experienced"
HEADLESS_FRAMES = 600  # `--headless` without `--frames` stops after 10 s of play, never runs on unseen
INVISIBLE_DRIVERS = ("offscreen", "dummy")  # SDL video drivers that open no window


# The smallest window whose text is readable. At 640x360 every screen's text fits, in 12 px type
# (hud_style.min_text_px; tests/game/test_hud_small_screens.py); under it the HUD is hard to read:
# at 480x270 and 320x240 its capitals are 4 px high, a REJECTED mark runs into the move's name,
# and the training screen's checklist and plot go off the bottom of the window. A smaller --size
# is said, not refused (a board's 480x320 screen has no larger window to give); the window a
# player drags is kept at least this large, or at least the --size asked for.
MIN_WINDOW = (640, 360)


def parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in arguments.window_size(text).lower().split("x"))
    except argparse.ArgumentTypeError as exc:  # one line naming --size, as before
        raise InputError(f"--size {text!r}: {exc}") from None
    return w, h


def parse_window_size(text: str, headless: bool, command: str) -> tuple[int, int]:
    """`--size` for `command`; a window (not --headless) under MIN_WINDOW is said in one line."""
    w, h = parse_size(text)
    if not headless and (w < MIN_WINDOW[0] or h < MIN_WINDOW[1]):
        print(f"quickjab {command}: --size {w}x{h}: under {MIN_WINDOW[0]}x{MIN_WINDOW[1]} the text is hard to read "
              "and some of it runs off the window", file=sys.stderr)
    return w, h


def open_window(size: tuple[int, int], flags: int, headless: bool, command: str) -> None:
    """The display at `size`: a window (not --headless) must show (check_visible_window), and
    it cannot be dragged below MIN_WINDOW (or below `size`, where that is smaller)."""
    import pygame

    pygame.display.set_mode(size, flags)
    if not headless:
        check_visible_window(command)
        keep_window_at_least((min(size[0], MIN_WINDOW[0]), min(size[1], MIN_WINDOW[1])))


def keep_window_at_least(size: tuple[int, int] = MIN_WINDOW) -> None:
    """Stop the (resizable) window being dragged below `size`, where the HUD cannot be read
    (MIN_WINDOW). pygame-ce's Window for the display's window; where it has none (an older
    pygame) or the video driver refuses, the window stays as it is: nothing breaks for it."""
    import warnings

    import pygame

    try:
        with warnings.catch_warnings():  # from_display_module is marked for removal in a later pygame-ce
            warnings.simplefilter("ignore", DeprecationWarning)
            window = pygame.Window.from_display_module()
        window.minimum_size = size
    except (AttributeError, pygame.error):
        pass


# what a headless run of each command needs to be of use: `train` runs until its walk is over
HEADLESS_HINT = {"play": " --frames 600", "scope": " --frames 600", "train": ""}


def check_visible_window(command: str) -> None:
    """A window was asked for but SDL fell back to a driver that shows nothing (no display: a
    server, an SSH session): say so and stop, rather than run unseen forever. Choosing such a
    driver on purpose (SDL_VIDEODRIVER=dummy) is allowed."""
    import pygame

    driver = pygame.display.get_driver()
    if driver in INVISIBLE_DRIVERS and os.environ.get("SDL_VIDEODRIVER", "").lower() != driver:
        raise InputError(f"no display: SDL opened its {driver!r} video driver, so no window would show; "
                         f"run it where a display is (DISPLAY / WAYLAND_DISPLAY), or use `quickjab {command} --headless{HEADLESS_HINT[command]}` "
                         f"(in a clone: .venv/bin/quickjab {command} --headless{HEADLESS_HINT[command]})")


def headless_frames(frames: int | None, headless: bool, command: str) -> int | None:
    """The frame count to run: a headless run without --frames ends after HEADLESS_FRAMES."""
    if frames is None and headless:
        print(f"quickjab {command}: --headless without --frames: stopping after {HEADLESS_FRAMES} frames", file=sys.stderr)
        return HEADLESS_FRAMES
    return frames


# Sources paced by a device, whatever clock they are given: under --headless's virtual clock, which
# runs as fast as the machine does, a minute of frames passed in seconds with a few samples in
# them (scope said 0 samples/s, train saved templates of held copies). Such a source runs on the
# real clock, with or without a window. Told by the source opened, not the URL typed: the default
# (no --source) is the first Wiimote found, and --demo opens the keyboard whatever --source says.
LIVE_SCHEMES = ("serial", "wiimote")


def is_live(url: str) -> bool:
    """Whether a source URL names a device that delivers at its own pace (LIVE_SCHEMES; a
    pyserial loop:// delivers at once)."""
    return url.split("://", 1)[0].lower() in LIVE_SCHEMES and "://loop://" not in url


def open_on_run_clock(command: str, headless: bool, open_sources: Callable[[object], T],
                      sources_of: Callable[[T], list]) -> tuple[object, T]:
    """(clock, what `open_sources(clock)` returned): a real clock with a window; the virtual clock
    of --headless (reproducible) unless a source it opened is a live device (`is_live`), which is
    said in one line, closed and opened again on the real clock."""
    from engine.clock import RealClock, VirtualClock

    clock = VirtualClock() if headless else RealClock()
    opened = open_sources(clock)
    live = [s.url for s in sources_of(opened) if is_live(s.url)] if headless else []
    if not live:
        return clock, opened
    print(f"quickjab {command}: {live[0]} is a live device: --headless runs on the real clock with it "
          "(its samples come at the device's pace)", file=sys.stderr)
    for source in sources_of(opened):
        source.close()
    clock = RealClock()
    return clock, open_sources(clock)


def headless_env() -> None:
    """No window, no sound device: SDL's dummy drivers (set before pygame initialises)."""
    os.environ["SDL_VIDEODRIVER"] = "dummy"
    os.environ["SDL_AUDIODRIVER"] = "dummy"


def wants_sound(args: argparse.Namespace) -> bool:
    """Sound is played unless `--no-sound` or `--headless` (which has no audio device)."""
    return not args.no_sound and not args.headless


def init_pygame(sound: bool) -> None:
    """What the game uses of pygame: the display (with its events and keys) and fonts, and the
    mixer only when `sound`. pygame.init() also opened the audio device with `--no-sound` and
    `--headless` (its thread mixing silence all match long) and the joystick subsystem (which
    nothing reads), and pygame.quit() then waited ~33 ms for the audio thread. The mixer opens as
    pygame.init() opened it, with pygame's defaults; where that fails, game.sound.Sounds tries
    its own settings and else stays silent, as before."""
    import pygame

    pygame.display.init()
    pygame.font.init()
    if sound:
        try:
            pygame.mixer.init()
        except pygame.error:
            pass


def open_player_source(url: str | None, demo: bool, seed: int, clock) -> tuple[object, str]:
    """The source to play with, and why the keyboard was taken instead of a Wiimote ("" when
    it was not): the caller says it in one line with what that means for its command."""
    import game.keyboard_source  # noqa: F401 - registers keyboard://
    from engine.sensors import SourceError, SourceState, open_source

    if demo:
        return open_source(f"{DEMO_SOURCE}&seed={seed}", clock=clock), ""
    if url is not None:
        if url.startswith("keyboard://") and "seed=" not in url:
            url += ("&" if "?" in url else "?") + f"seed={seed}"
        return open_source(url, clock=clock), ""
    try:
        source = open_source(DEFAULT_SOURCE, clock=clock)
    except SourceError as exc:
        why = str(exc).split(";")[0]  # the pairing help after it is `quickjab devices`'s
    else:
        if source.state is not SourceState.DISCONNECTED:
            return source, ""
        source.close()
        why = f"{DEFAULT_SOURCE}: no Wiimote connected"
    return open_source(f"{KEYBOARD_SOURCE}?seed={seed}", clock=clock), why


def toggle_fullscreen() -> None:
    """F11: the window to fullscreen and back, where SDL's video driver can (pygame's own call
    raised "That operation is not supported" out of the game loop on the others: kmsdrm, a
    Raspberry Pi's console without a desktop, and the dummy and offscreen drivers); where it
    cannot, one line on the console (once for each driver: not one a press) and the game goes on
    in its window."""
    import pygame

    try:
        pygame.display.toggle_fullscreen()
    except pygame.error as exc:
        driver = pygame.display.get_driver()
        if driver not in NO_FULLSCREEN_SAID:
            NO_FULLSCREEN_SAID.add(driver)
            print(f"quickjab: F11: no fullscreen with SDL's {driver!r} video driver ({exc})", file=sys.stderr)


NO_FULLSCREEN_SAID: set[str] = set()  # the video drivers F11 has been said not to work with


SLOW_SHARE = 0.1  # frames whose work passed their period: more than this share, the machine is slow
SLOW_AFTER_FRAMES = 300  # a run this long at least (5 s at 60 Hz): the first frames' loading is not the machine


# the window the low-power hint points at: the smallest whose text keeps its floor (game/hud_style.py
# FLOOR_DOWN_TO_U: 720 * 0.625 = 450 high); under it the HUD is "a picture of the game" (docs/game.md)
SMALL_WINDOW = (800, 450)
SMALLER_BY = 0.75  # pointed at only when it leaves at most this share of the window's pixels


def slow_machine_hint(budget: FrameBudget, low_power: bool, size: tuple[int, int] | None = None) -> str:
    """One line for a run whose frames often took longer than their period (a small board
    rendering the full game), pointing at what to change; "" for a run that kept up. `size` is
    the window's at the end: one that SMALL_WINDOW would hardly shrink (a Pi's 800x480 screen)
    or is already smaller is not told to shrink."""
    if budget.frames < SLOW_AFTER_FRAMES or budget.frame_overruns <= SLOW_SHARE * budget.frames:
        return ""
    share = f"{100 * budget.frame_overruns / budget.frames:.0f} % of the frames took longer than {budget.frame_period_ms:.1f} ms"
    if not low_power:
        return f"{share}: this machine may play better with --low-power (a 30 Hz render, half-size flat shading)"
    w, h = SMALL_WINDOW
    if size is not None and w * h > SMALLER_BY * size[0] * size[1]:
        return f"{share} even in low power in a {size[0]}x{size[1]} window (F3 shows which stage runs over)"
    return f"{share} even in low power: a smaller window (--size {w}x{h}) draws less"


def say_if_slow(args: argparse.Namespace, budget: FrameBudget) -> None:
    """`play`'s last line for a run whose frames often overran (slow_machine_hint, told the
    window's size); none under the virtual clock or --headless, whose frames do not keep the
    machine's pace."""
    import pygame

    window = pygame.display.get_surface() if pygame.display.get_init() else None
    size = window.get_size() if window is not None else None
    hint = "" if args.virtual_clock or args.headless else slow_machine_hint(budget, args.low_power, size)
    if hint:
        print(f"quickjab play: {hint}", file=sys.stderr)


def kernels_line() -> str:
    """One line when a C kernel built for this session (engine/native.py) runs on numpy for a
    reason the player did not choose (no C compiler, no writable cache, a failed build): the
    game plays, its physics and recognition more slowly, which only `quickjab bench` said. ""
    when they run native, or QUICKJAB_NO_NATIVE / QUICKJAB_NO_JIT asked for numpy."""
    from engine import native

    if native.disabled() or not any(v.startswith("numpy") for v in native.status().values()):
        return ""
    return f"{native.describe()}: the game plays, more slowly (docs/performance.md)"


@contextmanager
def slow_hint_at_the_end(args: argparse.Namespace, budget: FrameBudget) -> Iterator[None]:
    """say_if_slow when the loop inside ends, by its frame count, the window closed or Ctrl-C in
    the terminal (often how a run too slow to play is ended: it said nothing then); not after
    an error."""
    try:
        yield
    except KeyboardInterrupt:
        say_if_slow(args, budget)
        raise
    say_if_slow(args, budget)


def save_image(surface, path: str | os.PathLike, what: str = "the screenshot") -> None:
    """`surface` as an image file, its format from the suffix as pygame.image.save picks it.
    Encoded in memory and written by Python: pygame's own writing ignores a failed write (a full
    disk left a truncated PNG, and "wrote"). A file that cannot be written is an InputError
    naming it, not a pygame.error traceback."""
    import io

    import pygame

    buf = io.BytesIO()
    try:
        pygame.image.save(surface, buf, os.path.basename(path))
        os.makedirs(os.path.dirname(path) or ".", exist_ok=True)  # a folder not made yet is made, as for every output
        with open(path, "wb") as f:
            f.write(buf.getvalue())
    except (OSError, pygame.error) as exc:
        raise InputError(f"{path}: cannot save {what} ({getattr(exc, 'strerror', None) or exc})") from None


def save_screenshot(path: str) -> None:
    """The window's last frame to `path` (save_image)."""
    import pygame

    save_image(pygame.display.get_surface(), path)


def played_files(args: argparse.Namespace) -> list[str | None]:
    """The files a match reads: the templates, the graph, and what its source URLs replay."""
    from engine.sensors.source import url_file

    urls = [getattr(args, key, None) for key in ("source", "source2")]
    return [getattr(args, "templates", None), getattr(args, "graph", None), *(url_file(u) for u in urls if u)]


def run_session(args: argparse.Namespace, caption: str, open_sources: Callable[[object], list],
                make_session: Callable[..., object]) -> int:
    """_run_session, ended by SIGTERM (`kill`, `timeout`, a service manager) or SIGHUP (the
    terminal closed) as by Ctrl-C: the screenshot and trace written, the slow-machine hint, exit
    130. SIGHUP's default ended the run on the spot, with none of it; so did SIGTERM before the
    window, and in the loop SDL made it a closed window (exit 0), depending on SDL's build."""
    from engine.interrupt import stop_signals_as_ctrl_c

    with stop_signals_as_ctrl_c():  # before pygame starts: SDL then leaves SIGTERM alone
        return _run_session(args, caption, open_sources, make_session)


def _run_session(args: argparse.Namespace, caption: str, open_sources: Callable[[object], list],
                 make_session: Callable[..., object]) -> int:
    """What one- and two-player play share: the window (or none: --headless, which stops after
    HEADLESS_FRAMES without --frames), a clear error when SDL shows no window, the clock, the
    templates line, the loop, then the screenshot and trace, and the sources closed.
    `open_sources(clock)` returns the sources (opened before the window: a bad URL is an
    error, not a window that opens and closes); `make_session(sources, clock, size,
    surface_provider)` builds the session."""
    size = parse_window_size(args.size, args.headless, "play")
    if args.frames is not None and args.frames < 1:
        raise InputError("--frames must be at least 1")
    refuse_overwriting({"--screenshot": args.screenshot, "--trace": args.trace}, played_files(args))
    frames = headless_frames(args.frames, args.headless, "play")
    if args.headless:
        headless_env()
    import pygame

    from engine.clock import VirtualClock

    sources: list = []
    try:
        if args.virtual_clock:
            clock = VirtualClock()
            sources.extend(open_sources(clock))
        else:
            clock, opened = open_on_run_clock("play", args.headless, open_sources, list)
            sources.extend(opened)
        init_pygame(wants_sound(args))
        flags = pygame.RESIZABLE | (pygame.FULLSCREEN if args.fullscreen and not args.headless else 0)
        open_window(size, flags, args.headless, "play")
        pygame.display.set_caption(caption)
        session = None
        try:  # Ctrl-C while the match loads (seconds on a slow board) writes the files as in the loop
            session = make_session(sources, clock, size, pygame.display.get_surface)
            _ready(session, args)
        except KeyboardInterrupt:
            write_run_files(args, session)
            raise
        try:
            with slow_hint_at_the_end(args, session.loop.budget):
                session.loop.run(frames=frames)
        finally:
            write_run_files(args, session)
    finally:
        for source in sources:
            source.close()
        pygame.quit()
    return 0


def _ready(session: Session, args: argparse.Namespace) -> None:
    """A built session made ready for its loop: the templates and kernels lines said, the F3
    overlay and F11 set, and one frame drawn before the loop's clock starts: the first draw builds
    the ring's static layers and the HUD's fonts (26 ms here against 2.6 for a frame, ~120 ms on a
    core shared five ways), which in the loop's first frame dropped steps on a slow board."""
    for line in [*session.templates_lines(), kernels_line()]:
        if line:
            print(f"quickjab play: {line}", file=sys.stderr)
    session.hud_state.show_budget = args.budget
    session.on_toggle_fullscreen = toggle_fullscreen
    session.render(0.0)


def write_run_files(args: argparse.Namespace, session: Session | None) -> None:
    """The `--screenshot` (what the window shows) and the `--trace` of a match whose window
    opened, at its end: by its frame count, the window closed, Ctrl-C or SIGTERM, also one before
    the loop's first frame (`session` None: not built yet). A trace of no frames is still written,
    as one cut in the loop's first frame is, so that an earlier run's file is not taken for this
    one's, and its line says it holds no frames."""
    from engine.budget import FrameBudget
    from engine.trace import write_chrome_trace

    if args.screenshot:
        save_screenshot(args.screenshot)
        print(f"quickjab play: wrote {args.screenshot}", file=sys.stderr)
    if args.trace:
        budget = session.loop.budget if session is not None else FrameBudget()
        write_chrome_trace(budget, args.trace)
        empty = "" if budget.frames else " (no frames: ended before the first)"
        print(f"quickjab play: wrote {args.trace}{empty}", file=sys.stderr)
