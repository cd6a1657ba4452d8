"""The two-player scene: the renderer (full or low power) under a side-on camera that follows
the boxers' line, so player 1 is always on the left, player 2 on the right, neither hiding the
other.

The camera cuts between 8 views around the ring (game.camera.side_on_camera) rather than
panning: each view's static layers (arena, crowd, canvas, ropes) take milliseconds to draw, so
they are drawn once per view and kept, and a cut costs nothing after the first.
"""

from __future__ import annotations

import numpy as np
import pygame

from game.camera import side_on_camera, side_on_heading
from game.render import Renderer
from game.render_low_power import LowPowerRenderer

ROOT = 0  # the joint whose floor position places a boxer (the pelvis)


class SideOnFraming:
    """Mixed into a Renderer: before drawing, pick the view for the boxers' line and swap in
    its camera and cached static layers."""

    heading: int | None = None
    # side-on, neither boxer stands in front of the other: which one is "near" is arbitrary,
    # so neither is drawn translucent (the one-player view's see-through near boxer)
    see_through = False

    def draw(self, surf: pygame.Surface, bodies: list[np.ndarray]) -> None:
        size = surf.get_size()
        views = self.__dict__.setdefault("_views", {})  # heading -> (camera, static, front)
        if getattr(self, "_views_size", None) != size:
            views.clear()
            self._views_size = size
        p1, p2 = bodies[0][ROOT], bodies[1][ROOT]
        heading = side_on_heading(np.array([p1[0], p1[2]]), np.array([p2[0], p2[2]]), self.heading)
        if heading != self.heading or self.camera.size != size:
            if self.heading is not None and self._static is not None:
                views[self.heading] = (self.camera, self._static, self._front)
            cached = views.get(heading)
            if cached is not None and cached[0].size == size:
                self.camera, self._static, self._front = cached
            else:
                self.camera, self._static, self._front = side_on_camera(size, heading), None, None
            self.heading = heading
        super().draw(surf, bodies)


class SideOnRenderer(SideOnFraming, Renderer):
    pass


class SideOnLowPowerRenderer(SideOnFraming, LowPowerRenderer):
    pass
