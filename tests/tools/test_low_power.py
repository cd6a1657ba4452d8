"""Low-power mode does what the issue says: simulation at 60 Hz, rendering at 30 Hz on a
half-size surface scaled to the window, flat shading without antialiasing, fewer solver
iterations, the HUD naming the mode; and the headless target keeps its size frame after frame."""

from __future__ import annotations

import numpy as np
import pygame

from game.render import OPPONENT_LOOK, PLAYER_LOOK
from game.render_low_power import LowPowerRenderer
from tools.scripted_match import build_session

SIZE = (640, 360)


def colour_count(surf: pygame.Surface, rgb: tuple[int, int, int]) -> int:
    px = pygame.surfarray.pixels3d(surf)
    return int(np.all(px == np.array(rgb, dtype=px.dtype), axis=-1).sum())


def test_low_power_settings(match_graph) -> None:
    full = build_session(seed=1, size=SIZE, graph=match_graph)
    low = build_session(seed=1, size=SIZE, low_power=True, graph=match_graph)
    assert (full.loop.hz, full.loop.render_hz) == (60, 60)
    assert (low.loop.hz, low.loop.render_hz) == (60, 30)
    assert low.world.iterations < full.world.iterations
    assert isinstance(low.renderer, LowPowerRenderer) and low.renderer.antialias is False
    assert full.renderer.antialias is True and not isinstance(full.renderer, LowPowerRenderer)
    assert "LOW POWER" in low.hud_state.mode and "LOW POWER" not in full.hud_state.mode
    low.loop.run(steps=241)  # the first frame's one step, then 120 frames of two: no partial last frame
    assert low.loop.dropped_steps == 0
    # two 60 Hz steps per 30 Hz frame (the first frame runs one, to have a state to draw)
    assert dict(low.loop.budget.steps_per_frame) == {1: 1, 2: low.loop.frame_index - 1}
    stages = {s.name: s.budget_ms for s in low.loop.budget.stages}
    assert stages["render"] == 4.0


def test_low_power_draws_both_boxers_flat_on_a_half_size_surface(match_graph) -> None:
    s = build_session(seed=1, size=SIZE, low_power=True, graph=match_graph)
    for _ in range(5):
        s.loop.run(steps=60)
        # the window-size target keeps its size; the scene is drawn at half size
        assert s.target_surface().get_size() == SIZE
        assert s._low_power_surface.get_size() == (SIZE[0] // 2, SIZE[1] // 2)
    target = s.target_surface()
    # flat shading with a nearest-neighbour scale: the trunks keep their exact colours
    assert colour_count(target, PLAYER_LOOK.trunks) > 100
    assert colour_count(target, OPPONENT_LOOK.trunks) > 100
    # and the full renderer's antialiased silhouettes blend colours the flat one never makes
    full = build_session(seed=1, size=SIZE, graph=match_graph)
    full.loop.run(steps=300)
    low_colours = len(np.unique(pygame.surfarray.array3d(s._low_power_surface).reshape(-1, 3), axis=0))
    small = pygame.transform.scale(full.target_surface(), (SIZE[0] // 2, SIZE[1] // 2))
    full_colours = len(np.unique(pygame.surfarray.array3d(small).reshape(-1, 3), axis=0))
    assert low_colours < full_colours
