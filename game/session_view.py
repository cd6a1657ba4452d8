"""What a session draws once per rendered frame: the ring and the bodies (interpolated between
the last two steps with the loop's alpha), then the HUD from its typed state, on the display or
an offscreen surface. In low-power mode the scene is drawn at LOW_POWER_SCALE and scaled up, the
HUD's text drawn sharp at full size. Reads only; the stages never see it."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pygame

from engine.budget import FrameBudget

LOW_POWER_SCALE = 0.5  # the low-power mode renders at half size and scales up


class SessionView:
    def __init__(self, size: tuple[int, int], low_power: bool, renderer, hud,
                 surface_provider: Callable[[], pygame.Surface] | None = None):
        self.size = size
        self.low_power = low_power
        self.renderer = renderer
        self.hud = hud
        self.surface_provider = surface_provider
        self.offscreen: pygame.Surface | None = None
        self.low_power_surface: pygame.Surface | None = None

    def target_surface(self) -> pygame.Surface:
        if self.surface_provider is not None:
            return self.surface_provider()
        if self.offscreen is None:
            self.offscreen = pygame.Surface(self.size)
        return self.offscreen

    def _scene_surface(self, target: pygame.Surface) -> pygame.Surface:
        if not self.low_power:
            return target
        w, h = target.get_size()
        size = (max(1, int(w * LOW_POWER_SCALE)), max(1, int(h * LOW_POWER_SCALE)))
        # its own surface: the headless target is self.offscreen, which must keep its size
        if self.low_power_surface is None or self.low_power_surface.get_size() != size:
            self.low_power_surface = pygame.Surface(size)
        return self.low_power_surface

    def draw(self, alpha: float, prev_joints: list[np.ndarray], curr_joints: list[np.ndarray],
             hud_state, budget: FrameBudget) -> None:
        target = self.target_surface()
        surf = self._scene_surface(target)
        bodies = [prev_joints[i] + (curr_joints[i] - prev_joints[i]) * alpha for i in (0, 1)]
        self.renderer.draw(surf, bodies)
        if surf is not target:
            # the scene at half size, scaled up; the HUD's text drawn sharp at full size
            pygame.transform.scale(surf, target.get_size(), target)
        self.hud.draw(target, hud_state, budget)
        if self.surface_provider is not None and pygame.display.get_init() and pygame.display.get_surface() is target:
            pygame.display.flip()
