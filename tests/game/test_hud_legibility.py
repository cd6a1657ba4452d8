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


def drawn_texts(hud: Hud, monkeypatch) -> list[tuple[str, pygame.Rect]]:
    """Every string the HUD blits, with where it went."""
    seen: list[tuple[str, pygame.Rect]] = []
    blit = hud.blit

    def record(surf, text, size, pos, color=None, anchor="topleft"):
        rect = blit(surf, text, size, pos, color, anchor) if color is not None else blit(surf, text, size, pos, anchor=anchor)
        seen.append((text, rect))
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
    inside = [(t, r) for t, r in texts if r.colliderect(box)]
    assert any(LONG_URL in t for t, _ in inside) and any("resumes" in t for t, _ in inside)
    for text, rect in inside:
        assert box.contains(rect), (text, rect, box)
