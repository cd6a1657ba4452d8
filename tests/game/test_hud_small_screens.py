"""Every screen stays readable on a small window (a Raspberry Pi's 800x480 touchscreen, 800x450):
no text under game.hud_style.MIN_TEXT_PX (caps 8 px in pygame's default font), and none runs
into another text of its panel or out of its panel or the window (frames drawn through pygame's
dummy driver: the fonts and rectangles the game really draws)."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import numpy as np
import pygame
import pytest

from game.actions import load_library
from game.hud import Hud, HudState, SourceSnapshot
from game.hud_text import release_fonts
from game.hud_two_player import TwoPlayerHud
from game.keyboard_source import KEYMAPS, key_help
from game.match import MatchSnapshot
from game.render import Renderer
from game.skeleton import local_to_world

SMALL = [(800, 450), (800, 480)]
MIN_CAP_PX, MIN_LINE_PX = 8, 12  # pygame's default font at 16 px (game.hud_style.MIN_TEXT_PX)
P2_URL = "P2 keyboard://?profile=experienced&seed=4&keys=right"  # the two-player demo's seat 2
# the panels a text drawn straight on the screen must keep out of (the overlays cover the rest)
SOLID = ("clock", "keyboard banner", "missing banner", "recognition", "keys")


@pytest.fixture(scope="module")
def scene():
    lib = load_library()
    return [local_to_world(lib["guard"].posture(0), (0.0, -0.9, 0.0)),
            local_to_world(lib["guard"].posture(0), (0.0, 0.9, np.pi))]


def _cap_heights(monkeypatch, min_line_px: int) -> Iterator[dict[str, int]]:
    """The cap height (px) of the font each string was rendered in, the smallest if several;
    every font's line height at least `min_line_px`."""
    seen: dict[str, int] = {}

    class Font(pygame.font.Font):
        def render(self, text, *args, **kwargs):
            cap = self.metrics("H")[0][3]
            seen[text] = min(seen.get(text, cap), cap)
            assert self.get_linesize() >= min_line_px, (text, self.get_linesize())
            return super().render(text, *args, **kwargs)

    release_fonts()  # the fonts are shared: made again through the spy, and not kept after it
    monkeypatch.setattr(pygame.font, "Font", Font)
    yield seen
    release_fonts()


@pytest.fixture
def caps(monkeypatch) -> Iterator[dict[str, int]]:
    """The cap height of the font each string was rendered in; lines at least MIN_LINE_PX."""
    yield from _cap_heights(monkeypatch, MIN_LINE_PX)


def busy(n: int = 1, **kw) -> HudState:
    """A player's HUD with everything lit: a keyboard (its key legend and banner), a long URL,
    a battery, the templates line, a rejected motion's name and score, both marks."""
    st = HudState(source=SourceSnapshot(url=P2_URL if n == 2 else "keyboard://?profile=experienced&seed=3",
                                        state="connected", battery=0.8),
                  templates="templates: yours (13 moves)", keys=key_help(), mode="LOW POWER", **kw)
    st.mark({"event": "start", "action": "uppercut_l", "score": 0.31})
    st.mark({"event": "switch", "action": "uppercut_r", "score": 0.42, "from_frame": 17})
    st.mark({"event": "reject", "action": "uppercut_r", "score": 0.09})
    st.main_fill, st.supp_fill = 4, 33
    return st


def seat(n: int, **kw) -> HudState:
    st = busy(n, **kw)
    st.keys = key_help(KEYMAPS["left" if n == 1 else "right"])
    return st


def budget():
    """A real loop's frame budget over the session's stages (the F3 table's rows)."""
    from engine.clock import VirtualClock
    from engine.loop import FixedStepLoop
    from game.stages import STAGES

    loop = FixedStepLoop(VirtualClock())
    for spec in STAGES:
        loop.add_stage(spec.name, lambda s, dt: None, spec.budget_ms)
    loop.set_render(lambda a: None, 8.0)
    loop.run(frames=5)
    return loop.budget


def played_out(n: int = 1, **kw) -> HudState:
    """A HUD under SOURCE ENDED, offering Enter to play the replay again (its longest line)."""
    st = busy(n, disconnected=True, **kw)
    st.source = SourceSnapshot(url=P2_URL.replace("keyboard", "replay"), state="ended", rewinds=True)
    return st


SCREENS = {
    "match": lambda: (Hud(), busy(keyboard_banner=True)),
    "demo": lambda: (Hud(), busy(demo=True)),
    "budget": lambda: (Hud(), busy(show_budget=True)),
    "paused": lambda: (Hud(), busy(match=MatchSnapshot(paused=True), difficulty="adaptive")),
    "over": lambda: (Hud(), busy(match=MatchSnapshot(phase="over", winner=1, result="points"), difficulty="adaptive")),
    "count": lambda: (Hud(), busy(match=MatchSnapshot(phase="count", downed=(1,), count=7, knockdowns=(0, 2)))),
    "double count": lambda: (Hud(), busy(match=MatchSnapshot(phase="count", downed=(0, 1), count=7, knockdowns=(2, 2)))),
    "double KO": lambda: (Hud(), busy(match=MatchSnapshot(phase="over", result="double KO"), difficulty="adaptive")),
    "lost": lambda: (Hud(), busy(2, disconnected=True)),
    "two": lambda: (TwoPlayerHud(seat(2)), seat(1, names=("P1", "P2"))),
    "two budget": lambda: (TwoPlayerHud(seat(2)), seat(1, names=("P1", "P2"), show_budget=True)),
    "ended": lambda: (Hud(), played_out(match=MatchSnapshot(paused=True))),
    "two ended": lambda: (TwoPlayerHud(played_out(2)), seat(1, names=("P1", "P2"), match=MatchSnapshot(paused=True))),
    "two lost": lambda: (TwoPlayerHud(seat(2, disconnected=True)), seat(1, names=("P1", "P2"), match=MatchSnapshot(paused=True))),
    "two over": lambda: (TwoPlayerHud(seat(2)), seat(1, names=("P1", "P2"), match=MatchSnapshot(phase="over", winner=0, result="KO"))),
}


def check_layout(size, layout, panels, caps) -> None:
    """Every text at least MIN_CAP_PX high, inside its panel and the window, and clear of the
    other texts of its panel (and, drawn on the screen, of the solid panels)."""
    window = pygame.Rect((0, 0), size)
    assert layout
    for text, rect, panel in layout:
        assert caps.get(text, 0) >= MIN_CAP_PX, (text, caps.get(text))
        assert window.contains(rect), (text, rect, size)
        assert panels[panel].contains(rect), (text, rect, panel, panels[panel])
    for i, (text, rect, panel) in enumerate(layout):
        for other, other_rect, other_panel in layout[i + 1:]:
            assert not (panel == other_panel and rect.colliderect(other_rect)), (panel, text, rect, other, other_rect)
        if panel == "screen":
            for name, box in panels.items():
                assert not (name.startswith(SOLID) and rect.colliderect(box)), (text, rect, name, box)
    for name, box in panels.items():
        assert window.contains(box), (name, box, size)


@pytest.mark.parametrize("size", SMALL)
@pytest.mark.parametrize("screen", list(SCREENS))
def test_hud_text_is_readable_and_stays_in_its_panel_on_a_small_window(size, screen, scene, caps) -> None:
    pygame.init()
    surf = pygame.Surface(size)
    Renderer(size).draw(surf, scene)
    hud, st = SCREENS[screen]()
    hud.draw(surf, st, budget() if st.show_budget else None)
    small = sorted({t for t, c in caps.items() if c < MIN_CAP_PX})
    assert not small, f"text under {MIN_CAP_PX} px caps at {size}: {small}"
    hud.layout = []  # again, noting where each text goes
    hud.draw(surf, st, budget() if st.show_budget else None)
    check_layout(size, hud.layout, hud.panels, caps)


@pytest.mark.parametrize("size", SMALL)
@pytest.mark.parametrize("phase", ["show", "ready", "record", "done", "waiting"])
def test_the_training_screen_is_readable_on_a_small_window(size, phase, caps) -> None:
    from game.training import READY_STEPS, Trainer, TrainingScreen

    pygame.init()
    trainer = Trainer(["straight_l", "step_forward", "uppercut_r"] + ["hook_l"] * 10)
    trainer.phase, trainer.phase_step = ("done", 0) if phase == "waiting" else (phase, READY_STEPS // 2)
    trainer.waiting = phase == "waiting"
    trainer.recorded = {"straight_l": [np.zeros((96, 6))] * 5, "step_forward": [np.zeros((96, 6))] * 2}
    trainer.index = 1
    screen = TrainingScreen(load_library(), trainer, "keyboard://?profile=experienced&seed=4&auto=1", left_handed=True)
    screen.saved_to = "/home/player/.local/share/quickjab/profiles/a-rather-long-profile-name.npz"
    for k in range(60):
        screen.push_frame(np.sin(np.arange(6) + k / 5.0))
    surf = pygame.Surface(size)
    screen.layout = []
    screen.draw(surf)
    small = sorted({t for t, c in caps.items() if c < MIN_CAP_PX})
    assert not small, f"text under {MIN_CAP_PX} px caps at {size}: {small}"
    check_layout(size, screen.layout, {**screen.panels, "screen": surf.get_rect()}, caps)
    # the plot's legend no larger than the checklist beside it
    legend = [caps[t] for t, _, p in screen.layout if p == "plot"]
    listed = [caps[t] for t, _, p in screen.layout if t in ("step forward", "hook L")]
    assert legend and max(legend) <= min(listed), (legend, listed)


def test_the_text_floor_holds_down_to_800x450_and_shrinks_with_smaller_windows() -> None:
    # a 640x360 window (two players' legends side by side) and thumbnails are pictures of the game:
    # the 16 px floor there made the two key legends overlap
    from game.hud_style import MIN_TEXT_PX, min_text_px, text_scale

    assert [min_text_px(h / 720) for h in (720, 480, 450)] == [MIN_TEXT_PX] * 3
    assert min_text_px(360 / 720) == 12 and min_text_px(180 / 720) == 6
    assert text_scale(1.0) == 1.0 and text_scale(450 / 720) == MIN_TEXT_PX / 18
    assert text_scale(360 / 720) < MIN_TEXT_PX / 18


@pytest.mark.parametrize("size", [*SMALL, (640, 480), (800, 600), (1280, 720)])
def test_the_budget_overlay_clears_the_mode_line_and_the_key_legend(size, scene) -> None:
    """F3 in low power on a small window: the overlay's panel (its top was 130 u while the clock
    and the mode line under it stop shrinking) ran over "LOW POWER  DEMO" at 800x480; on a 4:3
    window it covered the player's own recognition panel."""
    pygame.init()
    surf = pygame.Surface(size)
    hud, st = Hud(), busy(show_budget=True, demo=True)
    hud.layout = []
    hud.draw(surf, st, budget())
    overlay = hud.panels["budget"]
    mode = [rect for text, rect, _ in hud.layout if text == "LOW POWER  DEMO"]
    assert mode and not overlay.colliderect(mode[0]), (overlay, mode)
    assert not overlay.colliderect(hud.panels["keys 1"]), (overlay, hud.panels["keys 1"])
    assert not overlay.colliderect(hud.panels["recognition 1"]), (overlay, hud.panels["recognition 1"])


@pytest.mark.parametrize("size", [(640, 360), *SMALL, (960, 540), (1280, 720)])
@pytest.mark.parametrize("strip", ["keyboard banner", "missing banner"])
def test_the_budget_overlay_clears_the_strip_under_the_clock(size, strip) -> None:
    """F3 with the amber strip under the clock (no Wiimote; a Nunchuk missing): the overlay's
    panel covered the strip's end ("...for left-hand moves") up to 1280x720."""
    pygame.init()
    st = busy(show_budget=True, demo=True, keyboard_banner=strip == "keyboard banner")
    if strip == "missing banner":
        st.source = SourceSnapshot(url="wiimote://", state="connected", battery=0.8,
                                   missing="no Nunchuk: plug it in for left-hand moves")
    hud = Hud()
    hud.draw(pygame.Surface(size), st, budget())
    overlay = hud.panels["budget"]
    assert not overlay.colliderect(hud.panels[strip]), (overlay, hud.panels[strip])
    assert pygame.Rect((0, 0), size).contains(overlay) and not overlay.colliderect(hud.panels["keys 1"])


def two_players_with_and_without_f3(size, scene) -> tuple[dict[bool, np.ndarray], TwoPlayerHud]:
    """A two-player frame's pixels with the F3 overlay off and on, and the HUD that drew the
    second (its panels and its layout of texts)."""
    pygame.init()
    frames = {}
    for shown in (False, True):
        surf = pygame.Surface(size)
        Renderer(size).draw(surf, scene)
        hud, st = TwoPlayerHud(seat(2)), seat(1, names=("P1", "P2"), show_budget=shown)
        hud.layout = []
        hud.draw(surf, st, budget())
        frames[shown] = pygame.surfarray.array3d(surf)
    return frames, hud


@pytest.mark.parametrize("size", [(640, 360), *SMALL, (960, 540), (1280, 720)])
def test_the_budget_overlay_gives_way_to_player_twos_panels(size, scene) -> None:
    """F3 with two players on a small window: the overlay's panel (on the right, like player 2's
    panels) covered player 2's recognition panel and key legend. Their pixels are now the same
    with F3 on as off; the chart gives way first, then the least loaded stages' rows."""
    frames, hud = two_players_with_and_without_f3(size, scene)
    mine = [hud.panels[name] for name in ("recognition 2", "keys 2")]
    for rect in mine:
        region = (slice(rect.left, rect.right), slice(rect.top, rect.bottom))
        assert (frames[True][region] == frames[False][region]).all(), (rect, hud.panels["budget"])
    rows = len(hud._rows_text)
    shown_rows = hud.budget_overlay.rows_shown
    assert 4 <= shown_rows <= rows  # at 800x450: the busiest stages, their numbers readable
    if size == (1280, 720):  # room for all of it: as before
        assert shown_rows == rows and hud._chart.get_height() == 90


@pytest.mark.parametrize("size", [(800, 450), (960, 540), (1920, 1080)])
def test_the_budget_overlay_gives_way_to_the_shared_key_line(size, scene) -> None:
    """F3 with two players at 800x450 and 960x540: the overlay's title ran over the shared "Esc
    pause  F3 budget  F11 fullscreen" line under the round clock. The line's pixels are now the
    same with F3 on as off; on a large window, where the line is clear of it, the overlay keeps
    the one-player overlay's place."""
    frames, hud = two_players_with_and_without_f3(size, scene)
    (line,) = [rect for text, rect, _ in hud.layout if text.startswith("Esc pause")]
    assert not hud.panels["budget"].colliderect(line), (line, hud.panels["budget"])
    region = (slice(line.left, line.right), slice(line.top, line.bottom))
    assert (frames[True][region] == frames[False][region]).all()
    one = Hud()
    one.draw(pygame.Surface(size), busy(show_budget=True), budget())
    moved = hud.panels["budget"].top != one.panels["budget"].top
    assert moved == (size != (1920, 1080)), (hud.panels["budget"], one.panels["budget"])


@pytest.mark.parametrize("size", [(640, 1080), (800, 1040), (1280, 720)])
@pytest.mark.parametrize("screen", ["budget", "two budget"])
def test_the_budget_overlay_stays_inside_a_window_narrow_for_its_height(size, screen) -> None:
    # its scale follows the window's height: at 640x1080 the panel (440 u) was wider than the
    # window, and its left column of text ran off the left edge
    pygame.init()
    surf = pygame.Surface(size)
    hud, st = SCREENS[screen]()
    hud.layout = []
    hud.draw(surf, st, budget())
    window = surf.get_rect()
    assert window.contains(hud.panels["budget"]), (size, hud.panels["budget"])
    texts = [(text, rect) for text, rect, panel in hud.layout if panel == "budget"]
    assert texts and all(window.contains(rect) for _, rect in texts), [t for t in texts if not window.contains(t[1])][:3]


@pytest.mark.parametrize("players", [1, 2])
def test_a_long_urls_source_line_keeps_its_state_whole(players) -> None:
    """At 800x450 a long URL's source line gave way in its middle, into its state ("...onnected,
    no Nunchuk"): the URL gives way now, the state after it stays whole."""
    pygame.init()
    url = "wiimote://00:1F:32:AB:CD:EF?profile=a-rather-long-profile-name&seed=12345"
    missing = "no Nunchuk: plug it in for left-hand moves"
    if players == 1:
        hud, st = Hud(), busy()
    else:
        hud, st = TwoPlayerHud(seat(2)), seat(1, names=("P1", "P2"))
    st.source = SourceSnapshot(url=url, state="connected", battery=0.8, missing=missing)
    hud.layout = []
    hud.draw(pygame.Surface((800, 450)), st, budget())
    (line,) = [text for text, _, _ in hud.layout if text.startswith("wiimote:")]
    assert "..." in line and line.endswith("  connected, no Nunchuk"), line


@pytest.mark.parametrize("size", [(640, 720), (800, 600), (800, 1040), (640, 1080), (1280, 720), (1920, 1080)])
@pytest.mark.parametrize("strip", ["keyboard banner", "missing banner"])
def test_the_amber_strip_covers_no_text(size, strip) -> None:
    """On windows narrow for their height the strip under the clock covered the templates line
    ("templates: yours (13 moves)"): it goes under the source's lines there, and stays where it
    was on the others."""
    pygame.init()
    st = busy(keyboard_banner=strip == "keyboard banner")
    if strip == "missing banner":
        st.source = SourceSnapshot(url="wiimote://", state="connected", battery=0.8,
                                   missing="no Nunchuk: plug it in for left-hand moves")
    hud = Hud()
    hud.layout = []
    hud.draw(pygame.Surface(size), st, budget())
    box = hud.panels[strip]
    assert [text for text, rect, panel in hud.layout if panel != strip and rect.colliderect(box)] == []
    assert pygame.Rect((0, 0), size).contains(box)
    st.templates = ""
    st.source = dataclasses.replace(st.source, url="k://")
    bare = Hud()
    bare.draw(pygame.Surface(size), st, budget())  # nothing under the clock to clear: where the strip goes
    if size[0] / size[1] >= 16 / 9:
        assert box == bare.panels[strip]


@pytest.fixture
def caps_any(monkeypatch) -> Iterator[dict[str, int]]:
    """`caps` without its 800x450 line-height floor: the cap height each string was rendered in."""
    yield from _cap_heights(monkeypatch, 0)


def test_the_smallest_window_keeps_every_screen_readable_and_inside_it(scene, caps_any) -> None:
    """At game.launch.MIN_WINDOW (640x360, the smallest window whose text is readable) every
    screen's text is of the window's floor (12 px type: caps 7 px; 4 px at 480x270 and 320x240,
    which are said) and stays inside its panel, clear of the others."""
    from game.hud_style import min_text_px
    from game.launch import MIN_WINDOW
    from game.training import READY_STEPS, Trainer, TrainingScreen

    pygame.init()
    assert MIN_WINDOW == (640, 360) and min_text_px(MIN_WINDOW[1] / 720) == 12
    # check_layout's own caps floor is 800x450's (8 px): it gets caps raised to it, and this
    # window's floor (7 px) is asserted on the real ones after it
    for name, make in SCREENS.items():
        surf = pygame.Surface(MIN_WINDOW)
        Renderer(MIN_WINDOW).draw(surf, scene)
        hud, st = make()
        hud.layout = []
        hud.draw(surf, st, budget() if st.show_budget else None)
        check_layout(MIN_WINDOW, hud.layout, hud.panels, {t: max(c, MIN_CAP_PX) for t, c in caps_any.items()})
        assert min(caps_any[t] for t, _, _ in hud.layout) >= 7, name
    for phase in ("show", "record", "done"):
        trainer = Trainer(["straight_l", "step_forward", "uppercut_r"] + ["hook_l"] * 10)
        trainer.phase, trainer.phase_step = phase, READY_STEPS // 2
        screen = TrainingScreen(load_library(), trainer, "keyboard://?profile=experienced&seed=4&auto=1")
        for k in range(60):
            screen.push_frame(np.sin(np.arange(6) + k / 5.0))
        surf = pygame.Surface(MIN_WINDOW)
        screen.layout = []
        screen.draw(surf)
        check_layout(MIN_WINDOW, screen.layout, {**screen.panels, "screen": surf.get_rect()},
                     {t: max(c, MIN_CAP_PX) for t, c in caps_any.items()})
        assert min(caps_any[t] for t, _, _ in screen.layout) >= 7, phase


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # pygame-ce's Window.from_display_module
def test_the_window_cannot_be_dragged_below_the_smallest() -> None:
    # a resizable window dragged to 320x240 would draw a HUD too small to read
    from game.launch import MIN_WINDOW, keep_window_at_least

    pygame.init()
    pygame.display.set_mode((800, 450), pygame.RESIZABLE)
    try:
        keep_window_at_least()
        window = pygame.Window.from_display_module()
        window.size = (320, 240)
        assert pygame.display.get_surface().get_size() == MIN_WINDOW
        window.size = (900, 500)
        assert pygame.display.get_surface().get_size() == (900, 500)
    finally:
        pygame.display.quit()
