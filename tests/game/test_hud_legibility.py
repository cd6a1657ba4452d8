"""What the HUD writes stays readable where the player reads it: inside its box, on a dark
ground over the bright canvas, in words that say what happened (text rectangles and pixels of
frames drawn through pygame's dummy driver)."""

from __future__ import annotations

import numpy as np
import pygame
import pytest

from game.actions import load_library
from game.hud import Hud, HudState, SourceSnapshot
from game.hud_two_player import TwoPlayerHud
from game.match import MatchSnapshot
from game.render import Renderer
from game.skeleton import local_to_world

LONG_URL = "P2 keyboard://?profile=experienced&seed=4&keys=right"  # the two-player demo's seat 2


@pytest.fixture(scope="module")
def scene():
    lib = load_library()
    return [local_to_world(lib["guard"].posture(0), (0.0, -0.9, 0.0)),
            local_to_world(lib["guard"].posture(0), (0.0, 0.9, np.pi))]


def drawn_texts(hud: Hud, monkeypatch) -> list[tuple[str, pygame.Rect, tuple]]:
    """Every string the HUD blits, with where it went and its colour."""
    from game.hud import TEXT

    seen: list[tuple[str, pygame.Rect, tuple]] = []
    blit = hud.blit

    def record(surf, text, size, pos, color=TEXT, anchor="topleft"):
        rect = blit(surf, text, size, pos, color, anchor)
        seen.append((text, rect, tuple(color)))
        return rect

    monkeypatch.setattr(hud, "blit", record)
    return seen


@pytest.mark.parametrize("size", [(1280, 720), (800, 450)])
@pytest.mark.parametrize("players", [1, 2])
def test_the_lost_controller_message_stays_inside_its_box(size, players, monkeypatch, scene) -> None:
    pygame.init()
    surf = pygame.Surface(size)
    Renderer(size).draw(surf, scene)
    lost = HudState(disconnected=True, source=SourceSnapshot(url=LONG_URL, state="disconnected"))
    if players == 1:
        hud, st = Hud(), lost
    else:
        hud, st = TwoPlayerHud(lost), HudState(names=("P1", "P2"), match=MatchSnapshot(paused=True))
    texts = drawn_texts(hud, monkeypatch)
    hud.draw(surf, st)
    box = hud.lost_box
    inside = [(t, r) for t, r, _ in texts if r.colliderect(box)]
    assert any(LONG_URL in t for t, _ in inside) and any("resumes" in t for t, _ in inside)
    for text, rect in inside:
        assert box.contains(rect), (text, rect, box)


def luminance(rgb: np.ndarray) -> np.ndarray:
    """WCAG relative luminance of sRGB pixels (..., 3) in 0-255."""
    c = rgb.astype(float) / 255.0
    lin = np.where(c <= 0.03928, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return lin @ np.array([0.2126, 0.7152, 0.0722])


def contrast(surf: pygame.Surface, rect: pygame.Rect, colour) -> float:
    """The contrast ratio of `colour` against the ground under `rect` (its median pixel: the
    letters cover the lesser part of their rectangle)."""
    rect = rect.clip(surf.get_rect())
    px = pygame.surfarray.array3d(surf)[rect.left:rect.right, rect.top:rect.bottom].reshape(-1, 3)
    ground = float(np.median(luminance(px)))
    text = float(luminance(np.array(colour)))
    hi, lo = max(ground, text), min(ground, text)
    return (hi + 0.05) / (lo + 0.05)


MENU_LINES = ("Esc or Home to resume", "Enter: a new match", "D: difficulty")


@pytest.mark.parametrize("size", [(1280, 720), (800, 450)])
@pytest.mark.parametrize("screen", ["paused", "over", "over_two"])
def test_menu_lines_under_a_banner_read_against_the_canvas(size, screen, monkeypatch, scene) -> None:
    pygame.init()
    surf = pygame.Surface(size)
    Renderer(size).draw(surf, scene)
    if screen == "paused":
        hud, st = Hud(), HudState(match=MatchSnapshot(paused=True), difficulty="normal")
    else:
        st = HudState(match=MatchSnapshot(phase="over", winner=0, result="KO"), difficulty="normal")
        hud = Hud() if screen == "over" else TwoPlayerHud(HudState())
    texts = drawn_texts(hud, monkeypatch)
    hud.draw(surf, st)
    lines = [(t, r, c) for t, r, c in texts if t.startswith(MENU_LINES)]
    assert len(lines) == (1 if screen == "over_two" else 2), texts
    for text, rect, colour in lines:
        ratio = contrast(surf, rect, colour)
        assert ratio >= 4.5, (text, rect, ratio)  # WCAG AA for normal text


@pytest.mark.parametrize("players", [1, 2])
@pytest.mark.parametrize("result, winner, title", [
    ("points", 0, "{} ON POINTS"), ("points", 1, "{} ON POINTS"), ("KO", 0, "KO - {}"), ("TKO", 1, "TKO - {}"),
    ("draw", None, "DRAW"), ("double KO", None, "DOUBLE KO - DRAW"),
])
def test_the_result_banner_reads_as_words(players, result, winner, title, monkeypatch) -> None:
    pygame.init()
    size = (1280, 720)
    surf = pygame.Surface(size)
    if players == 1:
        hud, names = Hud(), ("YOU WIN", "CPU WINS")
    else:
        hud, names = TwoPlayerHud(HudState()), ("P1 WINS", "P2 WINS")
    banners: list[str] = []
    banner = hud._banner
    monkeypatch.setattr(hud, "_banner", lambda s, text, *a, **k: banners.append(text) or banner(s, text, *a, **k))
    st = HudState(names=("YOU", "CPU") if players == 1 else ("P1", "P2"),
                  match=MatchSnapshot(phase="over", winner=winner, result=result))
    hud.draw(surf, st)
    assert banners == [title.format(names[winner]) if winner is not None else title]


def test_a_rejected_motion_is_not_shown_as_recognized_once_its_mark_fades(monkeypatch) -> None:
    pygame.init()
    surf = pygame.Surface((1280, 720))
    st = HudState()
    st.mark({"event": "start", "action": "uppercut_l", "score": 0.3})
    st.mark({"event": "reject", "action": "uppercut_l", "score": 0.09, "called_off": True})
    for _ in range(60):
        st.tick()  # the REJECT mark has gone out
    hud = Hud()
    texts = drawn_texts(hud, monkeypatch)
    hud.draw(surf, st)
    words = [t for t, _, _ in texts]
    assert "uppercut L" in words  # the motion it matched best is still named ...
    assert "RECOGNIZED" not in words and "REJECTED" in words  # ... as rejected, not recognized
    # a reject, then the next motion starts while the REJECT mark is still lit: the mark was
    # the last motion's, so it goes out with the new recognition beside it
    from game.hud import REJECT_COLOR

    st.mark({"event": "reject", "action": None})
    st.tick()
    st.mark({"event": "start", "action": "hook_r", "score": 0.2})
    surf.fill((0, 0, 0))
    texts.clear()
    hud.draw(surf, st)
    words = [t for t, _, _ in texts]
    assert "RECOGNIZED" in words and "REJECTED" not in words and "hook R" in words
    panel = pygame.Rect(0, 720 - 180, 360, 180)
    red = pygame.surfarray.array3d(surf)[panel.left:panel.right, panel.top:panel.bottom].reshape(-1, 3).astype(int)
    assert int((np.abs(red - np.array(REJECT_COLOR)).max(axis=1) <= 5).sum()) == 0  # no REJECT mark


def test_the_return_after_a_recognized_move_is_not_flagged_as_rejected() -> None:
    # after most punches the hand's return is a short motion the recognizer rejects (no template):
    # the panel flipped to "REJECTED no match" and the REJECT mark flashed after nearly every punch
    from game.hud_style import MARK_STEPS, TAIL_STEPS

    st = HudState()
    st.mark({"event": "start", "action": "straight_l", "score": 0.1})
    st.mark({"event": "end", "action": "straight_l"})
    for _ in range(10):
        st.tick()
    st.mark({"event": "reject", "action": None})
    assert st.action == "straight_l" and not st.rejected and st.reject_age == MARK_STEPS
    for _ in range(TAIL_STEPS):
        st.tick()
    st.mark({"event": "reject", "action": None})  # a motion long after: the player tried something
    assert st.rejected and st.action == "no match" and st.reject_age == 0
    st.mark({"event": "start", "action": "hook_r"})
    st.mark({"event": "reject", "action": "hook_r", "called_off": True})  # a start called off: shown
    assert st.rejected and st.reject_age == 0
