"""The arena's static layers, drawn once per window size (game/render.py caches them).

`build_layers` returns the back layer (arena glow, crowd, apron, canvas and the ropes and
posts behind the boxers) and the front layer (the ropes and posts nearer the camera than the
ring's centre, opaque over a colour key), so the renderer blits one before the boxers and the
other after them.
"""

from __future__ import annotations

import numpy as np
import pygame

from game.camera import Camera

RING_HALF = 3.0  # inside the ropes
APRON_HALF = 3.55
POST_HALF = 3.15
ROPE_HEIGHTS = (0.55, 0.9, 1.25)
POST_HEIGHT = 1.4

KEY = (255, 0, 255)


def poly(surf: pygame.Surface, color, pts: np.ndarray, width: int = 0) -> None:
    """A polygon from an array of screen points."""
    pygame.draw.polygon(surf, color, np.asarray(pts).tolist(), width)


def shade(c: tuple[int, int, int], k: float) -> tuple[int, int, int]:
    """Darken (k < 1) or lighten (k > 1, towards white) a colour."""
    if k <= 1.0:
        return (int(c[0] * k), int(c[1] * k), int(c[2] * k))
    t = min(1.0, k - 1.0)
    return (int(c[0] + (255 - c[0]) * t), int(c[1] + (255 - c[1]) * t), int(c[2] + (255 - c[2]) * t))


def build_layers(cam: Camera) -> tuple[pygame.Surface, pygame.Surface]:
    """(back, front): the static scene behind the boxers and the ropes in front of them."""
    w, h = cam.size
    back = _backdrop(w, h)
    _draw_crowd(back, cam)
    _draw_ring_floor(back, cam)
    # the front layer is opaque ropes over a colour key: an RLE-accelerated blit costs
    # only its few opaque pixels, where a per-pixel-alpha layer would cost the whole screen
    front = pygame.Surface((w, h))
    front.fill(KEY)
    front.set_colorkey(KEY, pygame.RLEACCEL)
    _draw_ropes_and_posts(back, front, cam)
    if pygame.display.get_init() and pygame.display.get_surface() is not None:
        # in the display's pixel format: a per-frame blit without conversion
        back = back.convert()
        front = front.convert()
        front.set_colorkey(KEY, pygame.RLEACCEL)
    return back, front


def _backdrop(w: int, h: int) -> pygame.Surface:
    """The arena: a dark gradient with a warm glow above the ring."""
    back = pygame.Surface((w, h))
    grad = np.linspace(0.0, 1.0, h)[:, None]
    top, bottom = np.array([14, 16, 26]), np.array([40, 34, 44])
    rows = (top * (1 - grad) + bottom * grad).astype(np.uint8)
    arr = np.broadcast_to(rows[None, :, :], (w, h, 3))
    pygame.surfarray.blit_array(back, np.ascontiguousarray(arr))
    glow = pygame.Surface((w, h), pygame.SRCALPHA)
    for i in range(6):
        r = int(h * (0.75 - i * 0.1))
        pygame.draw.ellipse(glow, (255, 220, 160, 10), (w // 2 - r * 1.3, int(h * 0.12) - r // 3, r * 2.6, r * 1.1))
    back.blit(glow, (0, 0))
    return back


def _draw_crowd(back: pygame.Surface, cam: Camera) -> None:
    """Rows of dim heads in the dark, seeded so every run draws the same crowd."""
    w, h = cam.size
    rng = np.random.default_rng(7)
    horizon = int(cam.project(np.array([0.0, 0.0, 14.0]))[0][1])
    for row in range(5):
        y = horizon - 20 - row * int(h * 0.045)
        n = 40 + row * 6
        xs = rng.uniform(0, w, n)
        for x in xs:
            shade_k = rng.uniform(0.5, 1.0)
            col = (int(60 * shade_k), int(52 * shade_k), int(64 * shade_k))
            rr = max(3, int(h * 0.012 * (1 - row * 0.1)))
            pygame.draw.circle(back, col, (int(x), int(y + rng.uniform(-4, 4))), rr)


def _draw_ring_floor(back: pygame.Surface, cam: Camera) -> None:
    """The apron with its skirt, and the canvas with a soft darker border and the logo circle."""
    w, h = cam.size
    a, c = APRON_HALF, RING_HALF
    apron = np.array([[-a, 0, -a], [a, 0, -a], [a, 0, a], [-a, 0, a]], dtype=float)
    poly(back, (70, 22, 30), cam.project(apron)[0])
    # the apron's skirt on the two sides that face the camera
    top, _ = cam.project(apron)
    low, _ = cam.project(apron + [0.0, -0.4, 0.0])
    for i, j in ((0, 1), (1, 2)):
        poly(back, (44, 12, 20), np.array([top[i], top[j], low[j], low[i]]))
    canvas = np.array([[-c, 0.002, -c], [c, 0.002, -c], [c, 0.002, c], [-c, 0.002, c]], dtype=float)
    poly(back, (198, 196, 184), cam.project(canvas)[0])
    # canvas shading: a soft darker border and the centre logo circle
    inner = canvas * [0.92, 1, 0.92]
    edge = pygame.Surface((w, h), pygame.SRCALPHA)
    poly(edge, (0, 0, 0, 28), cam.project(canvas)[0])
    poly(edge, (0, 0, 0, 0), cam.project(inner)[0])
    back.blit(edge, (0, 0))
    ang = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    circle = np.stack([1.1 * np.cos(ang), np.full_like(ang, 0.003), 1.1 * np.sin(ang)], axis=1)
    poly(back, (178, 176, 166), cam.project(circle)[0])
    poly(back, (150, 40, 50), cam.project(circle)[0], max(2, int(h / 240)))


def _draw_ropes_and_posts(back: pygame.Surface, front: pygame.Surface, cam: Camera) -> None:
    """The ropes and corner posts: those nearer the camera than the ring's centre go in `front`.
    Corner pads: red near the player's corner, blue at the opponent's."""
    posts = np.array([[-POST_HALF, 0, -POST_HALF], [POST_HALF, 0, -POST_HALF],
                      [POST_HALF, 0, POST_HALF], [-POST_HALF, 0, POST_HALF]], dtype=float)
    post_cols = [(200, 40, 40), (235, 235, 235), (40, 80, 210), (235, 235, 235)]
    depth_of = cam.project(posts)[1]
    mid_depth = cam.project(np.zeros(3))[1]
    # sides: (post i, post j); near sides go in the front layer
    for i in range(4):
        j = (i + 1) % 4
        near = (depth_of[i] + depth_of[j]) / 2 < mid_depth
        layer = front if near else back
        for k, hgt in enumerate(ROPE_HEIGHTS):
            ends = np.array([posts[i] + [0, hgt, 0], posts[j] + [0, hgt, 0]])
            xy, z = cam.project(ends)
            thick = max(2, int(cam.scale_at(z.mean()) * 0.035))
            col = (235, 235, 235) if k != 1 else (200, 40, 40)
            pygame.draw.line(layer, shade(col, 0.55), xy[0] + [0, thick * 0.5], xy[1] + [0, thick * 0.5], thick)
            pygame.draw.line(layer, col, xy[0], xy[1], thick)
    for i in range(4):
        near = depth_of[i] < mid_depth
        layer = front if near else back
        ends = np.array([posts[i], posts[i] + [0, POST_HEIGHT, 0]])
        xy, z = cam.project(ends)
        thick = max(4, int(cam.scale_at(z.mean()) * 0.16))
        pygame.draw.line(layer, (60, 60, 66), xy[0], xy[1], thick)
        pad = np.array([posts[i] + [0, 0.45, 0], posts[i] + [0, POST_HEIGHT - 0.05, 0]])
        pxy, _ = cam.project(pad)
        pygame.draw.line(layer, post_cols[i], pxy[0], pxy[1], int(thick * 1.25))
