"""`quickjab play` while it stands in for the game: the scope on the Wiimote, or on the demo
source with a banner. Delete this file when game/play.py becomes the real game."""

from __future__ import annotations

import numpy as np

import engine.sensors.source as source_mod
from engine.sensors import SourceError
from game.cli import main
from tools.scope import AXIS_COLORS, ScopeView


def no_wiimote(url, clock):
    raise SourceError("no Wiimote found")


def test_play_without_a_wiimote_shows_the_demo_source_and_a_banner(tmp_path, monkeypatch):
    import pygame

    monkeypatch.setitem(source_mod._factories, "wiimote", no_wiimote)
    out = tmp_path / "play.png"
    assert main(["play", "--headless", "--frames", "60", "--screenshot", str(out)]) == 0
    img = np.transpose(pygame.surfarray.array3d(pygame.image.load(str(out))), (1, 0, 2)).astype(int)
    view = ScopeView()
    status = img[: view.status_h]
    assert (np.abs(status - np.array([230, 190, 70])).max(axis=2) <= 8).sum() > 50  # the banner
    x0, y0, w, h = view.panel_rect(1)
    panel = img[y0: y0 + h, x0: x0 + w]
    assert (np.abs(panel - np.array(AXIS_COLORS[0])).max(axis=2) <= 30).sum() > 50  # demo traces
