"""`quickjab scope --source URL`: a live oscilloscope of both hands' acceleration.

The tool to use when wiring up a new sensor: one panel per hand scrolling the last few
seconds, one trace per axis (x red, y green, z blue) on a grid of whole g, with the source's
state (connected / reconnecting / ...) and its measured sample rate on top. It runs on the
engine's FixedStepLoop: a `poll` stage every 60 Hz step, the drawing as the render stage.

`--headless --frames N --screenshot out.png` runs N frames on a virtual clock under SDL's
dummy video driver (no window) and saves the last frame, so tests can check real pixels.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from engine import arguments
from engine.clock import RealClock, VirtualClock
from engine.errors import InputError, refuse_overwriting
from engine.interrupt import ends_as_ctrl_c
from engine.loop import FixedStepLoop
from engine.sensors import Sample, Source, SourceError, SourceState, open_source
from engine.sensors.rate import RateMeter
from engine.state_hash import state_hash
from engine.trace import write_chrome_trace
from tools.devices import no_device_hint

AXIS_COLORS = ((235, 85, 85), (90, 205, 90), (95, 145, 255))  # x, y, z
BACKGROUND = (16, 17, 22)
GRID = (48, 50, 60)
ZERO_LINE = (95, 98, 110)
TEXT = (220, 220, 225)
STATE_COLORS = {
    SourceState.CONNECTED: (90, 205, 90),
    SourceState.CONNECTING: (230, 190, 70),
    SourceState.RECONNECTING: (230, 190, 70),
    SourceState.DISCONNECTED: (235, 85, 85),
    SourceState.ENDED: (150, 150, 160),
}
READOUT_S = 0.25  # the numbers beside each hand's traces: their mean over this long (readable, not a blur)
HAND_NAMES = ("right hand (Wiimote / IMU 1)", "left hand (Nunchuk / IMU 2)")
CONNECT_TIMEOUT_S = 3.0  # a source that never connects (no port, no board) is an error by then
AUTO_RANGES = (4.0, 8.0, 16.0, 32.0)  # autoscale steps in g: 4 g is a Wiimote's, 16 g a phone's punch


def fit_text(font, text: str, width: int) -> str:
    """`text` cut (with "...") to fit `width` pixels in `font`: a long status never runs off."""
    if font.size(text)[0] <= width:
        return text
    while text and font.size(text + "...")[0] > width:
        text = text[:-1]
    return text + "..."


def grid_step(g_range: float, panel_h: float, label_h: float) -> int:
    """Whole g between labelled grid lines: 1 g, or more when the labels would touch."""
    step = 1
    while step < g_range and panel_h / 2 / g_range * step < label_h + 2:
        step *= 2
    return step


class SampleRing:
    """The last `capacity` samples, flattened to (3 * sensors,), in preallocated arrays."""

    def __init__(self, capacity: int, dim: int):
        self.t = np.zeros(capacity)
        self.x = np.zeros((capacity, dim))
        self.capacity = capacity
        self.count = 0  # samples added in total

    def extend(self, samples: list[Sample]) -> None:
        for s in samples[-self.capacity:]:
            i = self.count % self.capacity
            self.t[i] = s.t
            a = np.asarray(s.accel, dtype=np.float64).ravel()
            self.x[i, : min(len(a), self.x.shape[1])] = a[: self.x.shape[1]]
            self.count += 1

    def rows(self) -> np.ndarray:
        """Ring indices of the samples held, oldest first."""
        n = min(self.count, self.capacity)
        return np.arange(self.count - n, self.count) % self.capacity

    def since(self, t_from: float) -> tuple[np.ndarray, np.ndarray]:
        """(times, values) of the samples at or after t_from, oldest first."""
        idx = self.rows()
        keep = idx[self.t[idx] >= t_from]
        return self.t[keep], self.x[keep]


@dataclass
class ScopeView:
    """Pixel layout of the scope: a status bar, then one panel per hand."""

    width: int = 960
    height: int = 600
    seconds: float = 5.0  # time shown across the panel width
    g_range: float = 4.0  # panels show -g_range..+g_range
    auto_range: bool = False  # grow g_range (AUTO_RANGES) so the visible samples are not clipped
    status_h: int = 64
    margin: int = 44  # left margin for the g labels

    def panel_rect(self, hand: int) -> tuple[int, int, int, int]:
        h = (self.height - self.status_h) // 2
        return (self.margin, self.status_h + hand * h + 4, self.width - self.margin - 8, h - 10)

    def points(self, hand: int, t: np.ndarray, g: np.ndarray, now: float) -> np.ndarray:
        """(n, 2) pixel coordinates of samples (t, g) in a hand's panel, `now` at the right edge."""
        x0, y0, w, h = self.panel_rect(hand)
        px = x0 + w - (now - t) * (w / self.seconds)
        mid = y0 + h / 2
        py = mid - np.clip(g, -self.g_range, self.g_range) * (h / 2 / self.g_range)
        return np.column_stack([px, py])


class Scope:
    """Polls a source each step, keeps the last seconds of samples, draws them each frame."""

    def __init__(self, source: Source, view: ScopeView | None = None, banner: str = "",
                 connect_timeout: float | None = None):
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        import pygame  # imported here: `quickjab --help` need not load SDL

        self.pygame = pygame
        self.source = source
        self.view = view or ScopeView()
        self.banner = banner
        self.rate = RateMeter(window_s=1.0)
        cap = 8192  # 5 s at 1 kHz; more than any sensor we read
        self.ring = SampleRing(cap, 6)
        self.samples = 0
        self.quit = False
        try:
            pygame.display.init()
            self.screen = pygame.display.set_mode((self.view.width, self.view.height))
        except pygame.error as exc:
            source.close()
            raise InputError(f"cannot open a window ({exc}); without a display use --headless") from None
        from game.launch import check_visible_window

        try:
            check_visible_window("scope")  # SDL fell back to a driver that shows nothing
        except InputError:
            source.close()
            pygame.display.quit()
            raise
        pygame.font.init()
        pygame.display.set_caption(f"QuickJab scope: {source.url}")
        self.font = pygame.font.Font(None, 20)
        self.small = pygame.font.Font(None, 16)
        self.loop: FixedStepLoop | None = None
        self.final_state = source.state
        # never connected (no sample, never CONNECTED) after this long on the source's clock: stop
        self.connect_timeout = connect_timeout
        self.ever_connected = False
        self.timed_out = False
        self._t_open = source.clock()
        self.label_rects: list[tuple[int, int, int, int]] = []  # the g labels drawn last frame (tests)
        self.readouts: dict[int, tuple[float, float, float] | None] = {}  # each hand's readout, g (_readout)
        self.status_line = ""  # the state line drawn last (tests)

    # -- stages ----------------------------------------------------------------------------
    def poll(self, step: int, dt: float) -> None:
        samples = self.source.poll()
        self.ever_connected |= bool(samples) or self.source.state is SourceState.CONNECTED
        if (not self.ever_connected and self.connect_timeout is not None
                and self.source.clock() - self._t_open >= self.connect_timeout):
            self.timed_out = True
            if self.loop is not None:
                self.loop.stop()
        if samples:
            self.ring.extend(samples)
            self.rate.add(samples)
            self.samples += len(samples)

    def render(self, alpha: float) -> None:
        pg = self.pygame
        for event in pg.event.get():
            if event.type == pg.QUIT or (event.type == pg.KEYDOWN and event.key in (pg.K_ESCAPE, pg.K_q)):
                self.quit = True
                if self.loop is not None:
                    self.loop.stop()
        self.draw(self.source.clock())
        pg.display.flip()

    # -- drawing ---------------------------------------------------------------------------
    def draw(self, now: float) -> None:
        pg, v, screen = self.pygame, self.view, self.screen
        screen.fill(BACKGROUND)
        t, x = self.ring.since(now - v.seconds)
        if v.auto_range and len(t):
            peak = float(np.abs(x[:, : 3 * self.source.sensors]).max())
            v.g_range = next((r for r in AUTO_RANGES if r >= peak), AUTO_RANGES[-1])
        self.label_rects = []
        label_h = self.small.get_height()
        for hand in range(2):
            x0, y0, w, h = v.panel_rect(hand)
            step = grid_step(v.g_range, h, label_h)
            top = int(v.g_range)
            for gv in range(-top, top + 1):
                y = round(y0 + h / 2 - gv * h / 2 / v.g_range)
                pg.draw.line(screen, ZERO_LINE if gv == 0 else GRID, (x0, y), (x0 + w, y))
            placed: list[tuple[int, int]] = []
            # 0 and the ends first; a label that would touch one already placed is left out
            for gv in sorted(range(-top, top + 1, step), key=lambda g: (g != 0, abs(g) != top, abs(g))):
                y = round(y0 + h / 2 - gv * h / 2 / v.g_range)
                # kept inside its own panel: the -g label of one panel and the +g label of
                # the next would otherwise overlap in the gap between them
                ly = min(max(y - label_h // 2, y0), y0 + h - label_h)
                if any(ly < b + 1 and a < ly + label_h + 1 for a, b in placed):
                    continue
                label = self.small.render(f"{gv:+d} g", True, ZERO_LINE)
                screen.blit(label, (4, ly))
                placed.append((ly, ly + label_h))
                self.label_rects.append((4, ly, label.get_width(), label_h))
            # a vertical line every second, fixed to sample time so it scrolls with the traces
            for s in range(int(np.ceil(now - v.seconds)), int(np.floor(now)) + 1):
                px = round(x0 + w - (now - s) * w / v.seconds)
                pg.draw.line(screen, GRID, (px, y0), (px, y0 + h))
            pg.draw.rect(screen, GRID, (x0, y0, w, h), 1)
            screen.blit(self.small.render(HAND_NAMES[hand], True, TEXT), (x0 + 6, y0 + 4))
            if hand >= self.source.sensors:
                msg = self.font.render("no sensor on this hand", True, ZERO_LINE)
                screen.blit(msg, (x0 + w // 2 - msg.get_width() // 2, y0 + h // 2 - 24))
                continue
            if len(t) >= 2:
                for axis in range(3):
                    pts = v.points(hand, t, x[:, 3 * hand + axis], now)
                    pg.draw.lines(screen, AXIS_COLORS[axis], False, pts.tolist(), 2)
            self._readout(hand, t, x, now, x0 + w - 6, y0 + 4)
        self.draw_status(now)

    def _readout(self, hand: int, t: np.ndarray, x: np.ndarray, now: float, right: int, top: int) -> None:
        """Each axis's name and mean reading over the last READOUT_S, top right of the hand's
        panel, in its trace's colour: the traces alone could not tell 0.9 g from 1.0 g, which is
        how a serial IMU's axes are found (`?axes=`, firmware_bridge/README.md)."""
        recent = x[t >= now - READOUT_S, 3 * hand : 3 * hand + 3]
        mean = recent.mean(axis=0) if len(recent) else None
        self.readouts[hand] = None if mean is None else tuple(float(v) for v in mean)
        for axis in (2, 1, 0):  # right to left
            text = f"{'xyz'[axis]} {mean[axis]:+.2f}" if mean is not None else "xyz"[axis]
            img = self.small.render(text, True, AXIS_COLORS[axis])
            right -= img.get_width()
            self.screen.blit(img, (right, top))
            right -= 10

    def draw_status(self, now: float) -> None:
        screen, src = self.screen, self.source
        state = src.state
        color = STATE_COLORS.get(state, TEXT)
        measured = self.rate.rate_hz(now)
        nominal = f" (nominal {src.rate_hz:.0f} Hz)" if src.rate_hz else ""
        missing = src.missing()  # a Wiimote streaming without its Nunchuk: its traces lie flat
        line1 = (f"{state.value}{f', {missing}' if missing else ''}   {measured:6.1f} samples/s{nominal}   "
                 f"{self.samples} samples   {src.url}")
        self.status_line = line1
        width = self.view.width - 16
        screen.blit(self.font.render(fit_text(self.font, line1, width), True, color), (8, 6))
        parts = []
        if src.battery is not None:
            parts.append(f"battery {100 * src.battery:.0f}%")
        if src.stats:
            parts.append(" ".join(f"{k} {v}" for k, v in sorted(src.stats.items())))
        if self.loop is not None:
            last = self.loop.budget.last_frame_ms()
            parts.append(f"poll {last.get('poll', 0):.2f} ms  render {last.get('render', 0):.2f} ms  dropped steps {self.loop.dropped_steps}")
        screen.blit(self.small.render(fit_text(self.small, "   ".join(parts), width), True, TEXT), (8, 27))
        if self.banner:
            screen.blit(self.small.render(fit_text(self.small, self.banner, width), True, (230, 190, 70)), (8, 44))

    def state_hash(self) -> str:
        """Hash of what the scope holds: two headless runs of the same source must agree."""
        idx = self.ring.rows()
        loop = self.loop
        return state_hash(self.ring.t[idx], self.ring.x[idx], self.samples,
                          loop.step_index if loop else 0, loop.dropped_steps if loop else 0)

    def close(self) -> None:
        self.final_state = self.source.state  # before close() turns it to disconnected
        self.source.close()
        self.pygame.display.quit()


def run_scope(
    source: Source,
    *,
    clock: RealClock | VirtualClock,
    frames: int | None = None,
    screenshot: str | None = None,
    trace: str | None = None,
    banner: str = "",
    view: ScopeView | None = None,
    connect_timeout: float | None = None,
) -> Scope:
    """Run the scope until closed (or for `frames` frames); save a screenshot / trace if asked.
    With `connect_timeout`, a source that has not connected by then stops it (`scope.timed_out`)."""
    scope = Scope(source, view, banner, connect_timeout)
    loop = FixedStepLoop(clock=clock)
    scope.loop = loop
    loop.add_stage("poll", scope.poll, budget_ms=1.0)
    loop.set_render(scope.render, budget_ms=8.0)
    try:
        try:
            loop.run(frames=frames, until=lambda: scope.quit)
        finally:  # also on Ctrl-C, SIGTERM or SIGHUP (KeyboardInterrupt), as play writes its files
            _write_files(scope, screenshot, trace)
    finally:
        scope.close()
    return scope


def _write_files(scope: Scope, screenshot: str | None, trace: str | None) -> None:
    if screenshot:
        from game.launch import save_image

        save_image(scope.screen, screenshot)  # a file it cannot write whole: an InputError naming it
    if trace:
        write_chrome_trace(scope.loop.budget, trace)


def open_with_fallback(url: str, clock: Callable[[], float], default: str = "wiimote://",
                       fallback: str = "demo://") -> tuple[Source, str]:
    """Open `url`; if it is the `default` device URL and no such device can be opened (an
    error, or a source already disconnected), open `fallback` instead. Returns (source,
    banner); the banner says what happened and is empty unless the fallback was taken."""
    try:
        source = open_source(url, clock=clock)
    except SourceError as exc:
        if url != default:
            raise
        reason = str(exc)
    else:
        if source.state is not SourceState.DISCONNECTED or url != default:
            return source, ""
        reason = "disconnected"
        source.close()
    print(f"quickjab: no device at {default}: {reason}", file=sys.stderr)
    device = "Wiimote" if default.startswith("wiimote") else f"device at {default}"
    banner = f"No {device} found: showing the synthetic {fallback} source. Pair one, or pass --source URL."
    return open_source(fallback, clock=clock), banner


def headless_env() -> None:
    """No window, no sound: SDL's dummy drivers (set before pygame initialises)."""
    os.environ["SDL_VIDEODRIVER"] = "dummy"
    os.environ["SDL_AUDIODRIVER"] = "dummy"


def add_view_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--headless", action="store_true", help="no window: SDL dummy driver and a virtual clock (reproducible; a live serial:// or wiimote:// device runs on the real clock)")
    p.add_argument("--frames", type=arguments.positive_int, default=None, help="stop after N frames (default: until the window closes)")
    p.add_argument("--screenshot", type=arguments.image_file, metavar="PNG", help="save the last frame to this PNG")
    p.add_argument("--trace", type=arguments.trace_file, metavar="JSON", help="write the loop's Chrome trace here on exit (read it with `quickjab profile`)")
    p.add_argument("--seconds", type=arguments.float_range(0.0, 3600.0, lo_open=True), default=5.0, help="seconds shown across the window (default 5)")
    p.add_argument("--size", default="960x600", help="window size WxH (default 960x600)")
    p.add_argument("--range", type=arguments.float_range(0.1, 1000.0), default=None, metavar="G",
                   help="fixed scale of -G..+G g (default: 4 g, growing to 8, 16, 32 g when a signal would clip)")


def view_from_args(args: argparse.Namespace) -> ScopeView:
    try:
        w, h = (int(v) for v in arguments.window_size(args.size).lower().split("x"))
    except argparse.ArgumentTypeError as exc:
        raise InputError(f"--size {args.size!r}: {exc}") from None
    if w < 200 or h < 150 or not args.seconds > 0:
        raise InputError("--size must be at least 200x150 and --seconds positive")
    g_range = getattr(args, "range", None)
    if g_range is not None and not 0.5 <= g_range <= 64:
        raise InputError(f"--range {g_range}: expected 0.5..64 g")
    return ScopeView(width=w, height=h, seconds=args.seconds, g_range=g_range or 4.0, auto_range=g_range is None)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("scope", help="show a source's acceleration live (sensor oscilloscope)", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", default="demo://", help="source URL: wiimote://, serial:///dev/ttyACM0, replay://f.csv?loop=1, demo:// (default)")
    add_view_arguments(p)
    p.add_argument("--connect-timeout", type=arguments.positive_float, default=CONNECT_TIMEOUT_S, metavar="S",
                   help=f"exit with an error when the source has not connected after S seconds (default {CONNECT_TIMEOUT_S:g})")
    p.set_defaults(func=run)


@ends_as_ctrl_c  # before pygame starts: SDL made SIGTERM a closed window (exit 0)
def run(args: argparse.Namespace) -> int:
    from engine.sensors.source import url_file
    from game.launch import open_on_run_clock

    refuse_overwriting({"--screenshot": args.screenshot, "--trace": args.trace}, [url_file(args.source)])
    view = view_from_args(args)
    if args.headless:
        headless_env()
    clock, source = open_on_run_clock("scope", args.headless, lambda c: open_source(args.source, clock=c.seconds),
                                      lambda opened: [opened])
    from engine.recording import say_notes

    say_notes(source.file_notes, "scope")  # a replayed recording's row left out (a cut last row), as play says it
    if not args.connect_timeout > 0:
        raise InputError(f"--connect-timeout {args.connect_timeout}: must be positive")
    scope = run_scope(source, clock=clock, frames=args.frames, screenshot=args.screenshot, trace=args.trace, view=view,
                      connect_timeout=args.connect_timeout)
    if scope.timed_out:
        raise InputError(f"{args.source}: no device connected after {args.connect_timeout:g} s "
                         f"(source {scope.final_state.value}); {no_device_hint(args.source)}")
    print(f"scope: {scope.samples} samples from {args.source} in {scope.loop.frame_index} frames, "
          f"source {scope.final_state.value}", file=sys.stderr)
    if args.headless:  # reproducible: the same source and frame count give the same hash
        print(f"state {scope.state_hash()}")
    return 0
