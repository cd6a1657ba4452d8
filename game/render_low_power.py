"""The low-power renderer (`quickjab play --low-power`): the same scene with flat shading.

The profile of the full renderer (`quickjab bench frame`, cProfile of Session.render) shows
it is bound by Python calls, not by pixels: a limb is three filled capsules (outline, body,
highlight), each a polygon and two circles with small numpy arithmetic around them, so a
quarter-size surface alone saves little. Renderer(detailed=False) drops the highlight (render
p99 3.3 ms CPU in the scripted match, HUD and scale included); here a limb is one capsule, a
sphere two circles, the torso two polygons, the shadow a plain ellipse (no per-frame alpha
surface), nothing antialiased: 1.6 ms. The ring, ropes, flashes and draw order are the full
renderer's.
"""

from __future__ import annotations

import numpy as np
import pygame

from game.render import LIGHT_2D, BoxerLook, J, Renderer, shade

SHADOW = (120, 116, 106)  # the canvas colour darkened: an opaque shadow, no alpha blending


class LowPowerRenderer(Renderer):
    see_through = False  # exact flat colours, and no extra blit

    def __init__(self, size: tuple[int, int], detailed: bool = False):
        super().__init__(size, detailed=False)

    def _capsule(self, surf: pygame.Surface, a: np.ndarray, b: np.ndarray, ra: float, rb: float, color) -> None:
        self._capsule_fill(surf, a, b, ra, rb, color)

    def _sphere(self, surf: pygame.Surface, c: np.ndarray, r: float, color) -> None:
        pos = (float(c[0]), float(c[1]))
        pygame.draw.circle(surf, shade(color, 0.8), pos, r)
        pygame.draw.circle(surf, color, (pos[0] + LIGHT_2D[0] * r * 0.2, pos[1] + LIGHT_2D[1] * r * 0.2), r * 0.75)

    def _torso(self, surf: pygame.Surface, xy: np.ndarray, scale: np.ndarray, look: BoxerLook) -> None:
        sl, sr, hl, hr = xy[J["shoulder_l"]], xy[J["shoulder_r"]], xy[J["hip_l"]], xy[J["hip_r"]]
        k = float(scale[J["chest"]])
        widen_s = 1.0 + 0.07 * k / max(float(np.hypot(*(sr - sl))) / 2, 1e-6)
        widen_h = 1.0 + 0.05 * k / max(float(np.hypot(*(hr - hl))) / 2, 1e-6)
        ms, mh = (sl + sr) / 2, (hl + hr) / 2
        sl2, sr2 = ms + (sl - ms) * widen_s, ms + (sr - ms) * widen_s
        hl2, hr2 = mh + (hl - mh) * widen_h, mh + (hr - mh) * widen_h
        waist_l, waist_r = sl2 + (hl2 - sl2) * 0.62, sr2 + (hr2 - sr2) * 0.62
        pygame.draw.polygon(surf, look.skin, [tuple(sl2), tuple(sr2), tuple(waist_r), tuple(waist_l)])
        pygame.draw.polygon(surf, look.trunks, [tuple(waist_l), tuple(waist_r), tuple(hr2), tuple(hl2)])

    def _draw_shadows(self, surf: pygame.Surface, bodies: list[np.ndarray]) -> None:
        cam = self.camera
        for joints in bodies:
            feet = joints[[J["ankle_l"], J["ankle_r"], J["pelvis"]]]
            cx, cz = float(feet[:, 0].mean()), float(feet[:, 2].mean())
            ends = np.array([[cx - 0.45, 0.004, cz], [cx + 0.45, 0.004, cz], [cx, 0.004, cz - 0.32], [cx, 0.004, cz + 0.32]])
            xy = cam.project(ends)[0]
            lo, hi = xy.min(axis=0), xy.max(axis=0)
            if hi[0] - lo[0] > 2 and hi[1] - lo[1] > 2:
                pygame.draw.ellipse(surf, SHADOW, (float(lo[0]), float(lo[1]), float(hi[0] - lo[0]), float(hi[1] - lo[1])))
