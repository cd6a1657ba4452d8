"""The ring and the two boxers, drawn under a three-quarter camera.

The static part (arena, apron, canvas, the ropes behind the boxers) is drawn once per window
size into a cached surface; each frame blits it, draws shadows, both bodies as shaded limbs,
torso and head, sorted far to near, then the ropes in front and the hit flashes. Bodies come in
as (17, 3) world joints, already interpolated with the loop's alpha by the caller.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pygame
from pygame import gfxdraw

# the ring's geometry and colour helpers live with the static layers; re-exported here
from game.arena import APRON_HALF as APRON_HALF
from game.arena import KEY as KEY
from game.arena import POST_HALF as POST_HALF
from game.arena import POST_HEIGHT as POST_HEIGHT
from game.arena import RING_HALF as RING_HALF
from game.arena import ROPE_HEIGHTS as ROPE_HEIGHTS
from game.arena import build_layers, poly, shade
from game.camera import Camera
from game.skeleton import JOINTS

JOINT_NAMES = JOINTS  # the bodies' (17, 3) rows are in the skeleton's joint order
J = {name: i for i, name in enumerate(JOINT_NAMES)}

# When the near boxer (the player, seen from behind) covers this share of the far one's screen
# box, it is drawn at NEAR_OPACITY: the CPU shows through it in clinches.
OVERLAP_SHARE = 0.15
NEAR_OPACITY = 0.55
LIGHT_2D = np.array([-0.55, -0.83])  # the key light comes from the upper left of the screen
LIGHT_X, LIGHT_Y = float(LIGHT_2D[0]), float(LIGHT_2D[1])  # the same as plain floats (per limb)


@dataclass(frozen=True)
class BoxerLook:
    skin: tuple[int, int, int]
    trunks: tuple[int, int, int]
    gloves: tuple[int, int, int]
    shoes: tuple[int, int, int]


PLAYER_LOOK = BoxerLook(skin=(226, 170, 128), trunks=(200, 30, 40), gloves=(230, 40, 40), shoes=(30, 30, 34))
OPPONENT_LOOK = BoxerLook(skin=(150, 98, 66), trunks=(30, 80, 210), gloves=(35, 95, 235), shoes=(240, 240, 240))

# (joint a, joint b, radius m, part) drawn as capsules; part picks the colour
LIMBS = (
    ("hip_l", "knee_l", 0.08, "skin"), ("knee_l", "ankle_l", 0.065, "skin"),
    ("hip_r", "knee_r", 0.08, "skin"), ("knee_r", "ankle_r", 0.065, "skin"),
    ("neck", "head", 0.055, "skin"),
    ("shoulder_l", "elbow_l", 0.06, "skin"), ("elbow_l", "fist_l", 0.052, "skin"),
    ("shoulder_r", "elbow_r", 0.06, "skin"), ("elbow_r", "fist_r", 0.052, "skin"),
)
SPHERES = (("head", 0.125, "skin"), ("fist_l", 0.1, "gloves"), ("fist_r", 0.1, "gloves"),
           ("ankle_l", 0.07, "shoes"), ("ankle_r", 0.07, "shoes"))

# constant shapes, built once: a shadow ellipse round a boxer's feet (offsets on the canvas)
# and a hit flash's star (angles and the alternating tip/notch radius factors)
_SHADOW_ANG = np.linspace(0, 2 * np.pi, 20, endpoint=False)
SHADOW_RING = np.stack([0.45 * np.cos(_SHADOW_ANG), np.full_like(_SHADOW_ANG, 0.004),
                        0.32 * np.sin(_SHADOW_ANG)], axis=1)
_STAR_POINTS = 10
STAR_ANG = np.arange(2 * _STAR_POINTS) * np.pi / _STAR_POINTS
STAR_RADII = np.where(np.arange(2 * _STAR_POINTS) % 2 == 0, 1.0, 0.45)


def _aacircle(surf: pygame.Surface, color, x: float, y: float, r: float) -> None:
    """An antialiased circle outline: gfxdraw's (2-6 us a call) rather than pygame.draw's
    (11-36 us), on integer pixels as gfxdraw takes them."""
    gfxdraw.aacircle(surf, int(round(x)), int(round(y)), max(1, int(round(r))), color)


def facing(right: np.ndarray) -> np.ndarray:
    """right x up for a level (y = 0) unit vector: np.cross(right, (0, 1, 0)) to the bit (its
    products and differences, signed zeros included) from plain floats: np.cross cost ~15 us a
    boxer a frame, more than the eyes it places."""
    rx, rz = float(right[0]), float(right[2])
    return np.array((0.0 - rz, rz * 0.0 - rx * 0.0, rx - 0.0))


def _shifted(kind: int, args: tuple, offset: tuple[float, float]) -> tuple:
    """A primitive's arguments moved by -offset pixels (its points come first, or first two).
    Capsules and spheres stay plain float pairs (no numpy per limb: issue 14); the torso's and
    the eyes' points are already an array per body."""
    ox, oy = offset
    if kind == 0:
        (ax, ay), (bx, by) = args[0], args[1]
        return ((ax - ox, ay - oy), (bx - ox, by - oy), *args[2:])
    if kind == 1:
        (cx, cy) = args[0]
        return ((cx - ox, cy - oy), *args[1:])
    return (args[0] - np.array(offset), *args[1:])


def _capsule_edges(surf: pygame.Surface, a, b, ra: float, rb: float, color) -> None:
    """The antialiased sides and end caps of a capsule's outline."""
    ax, ay, bx, by = float(a[0]), float(a[1]), float(b[0]), float(b[1])
    dx, dy = bx - ax, by - ay
    n = math.sqrt(dx * dx + dy * dy)
    if n > 1e-6:
        px, py = -dy / n, dx / n
        pygame.draw.aaline(surf, color, (ax + px * ra, ay + py * ra), (bx + px * rb, by + py * rb))
        pygame.draw.aaline(surf, color, (ax - px * ra, ay - py * ra), (bx - px * rb, by - py * rb))
    _aacircle(surf, color, ax, ay, ra)
    _aacircle(surf, color, bx, by, rb)


@dataclass
class Flash:
    point: np.ndarray  # world
    age: int = 0
    strong: bool = True
    blocked: bool = False

    LIFE = 14


class Renderer:
    """Draws the ring and the boxers on a surface of any size (the window resizes)."""

    def __init__(self, size: tuple[int, int], detailed: bool = True):
        self.camera = Camera(size)
        # low-power mode: one flat colour per limb (no highlight pass), half the draw calls
        self.detailed = detailed
        self.antialias = detailed  # the full look smooths the silhouettes; low power does not
        self._static: pygame.Surface | None = None
        self._front: pygame.Surface | None = None
        self.flashes: list[Flash] = []
        self.looks = (PLAYER_LOOK, OPPONENT_LOOK)

    # -- static layers -------------------------------------------------------------------
    def resize(self, size: tuple[int, int]) -> None:
        if tuple(size) != self.camera.size:
            self.camera.resize(size)
            self._static = self._front = None

    _poly = staticmethod(poly)

    def _build_static(self) -> None:
        self._static, self._front = build_layers(self.camera)

    def screen_box(self, joints: np.ndarray, margin: float = 0.15) -> pygame.Rect:
        """The screen rectangle a body's joints (with `margin` metres around them) project to."""
        xy, z = self.camera.project(joints)
        pad = float(np.max(self.camera.scale_at(z))) * margin
        lo, hi = xy.min(axis=0) - pad, xy.max(axis=0) + pad
        return pygame.Rect(int(lo[0]), int(lo[1]), int(hi[0] - lo[0]), int(hi[1] - lo[1]))

    # -- per frame -----------------------------------------------------------------------
    def add_flash(self, point: np.ndarray, strong: bool = True, blocked: bool = False) -> None:
        self.flashes.append(Flash(np.asarray(point, dtype=float).copy(), strong=strong, blocked=blocked))

    def step_effects(self) -> None:
        """Age the hit flashes by one simulation step."""
        for f in self.flashes:
            f.age += 1
        self.flashes = [f for f in self.flashes if f.age < Flash.LIFE]

    def draw(self, surf: pygame.Surface, bodies: list[np.ndarray]) -> None:
        """Draw the scene; bodies[i] are boxer i's (17, 3) world joints."""
        self.resize(surf.get_size())
        if self._static is None:
            self._build_static()
        surf.blit(self._static, (0, 0))
        self._draw_shadows(surf, bodies)
        per_body = [self._boxer_prims(joints, self.looks[i % 2]) for i, joints in enumerate(bodies)]
        # the near boxer over the far one: keep what lies behind it, to show it through
        see_through = self._overlap(bodies) if self.see_through and len(bodies) == 2 else None
        behind = surf.subsurface(see_through[0]).copy() if see_through else None
        prims = sorted((p for body in per_body for p in body), key=lambda p: -p[0])
        self._draw_prims(surf, prims)
        if see_through is not None and behind is not None:
            box, far = see_through
            # the same region without the near boxer (background + the far boxer), blended over
            # it: the near boxer drawn at NEAR_OPACITY, so who hits whom stays visible
            self._draw_prims(behind, sorted(per_body[far], key=lambda p: -p[0]), offset=(float(box.left), float(box.top)))
            behind.set_alpha(int(255 * (1.0 - NEAR_OPACITY)))
            surf.blit(behind, box.topleft)
        surf.blit(self._front, (0, 0))
        self._draw_flashes(surf)

    see_through = True  # the near boxer translucent over the far one (low power: off, flat colours)

    def _overlap(self, bodies: list[np.ndarray]) -> tuple[pygame.Rect, int] | None:
        """(the near boxer's screen box, the far boxer's index) when the near one covers a
        good part of the far one, else None."""
        depth = [float(self.camera.project(b)[1].mean()) for b in bodies]
        near, far = (0, 1) if depth[0] < depth[1] else (1, 0)
        near_box = self.screen_box(bodies[near]).clip(self.screen_rect())
        far_box = self.screen_box(bodies[far])
        hidden = near_box.clip(far_box)
        if hidden.w * hidden.h < OVERLAP_SHARE * max(1, far_box.w * far_box.h):
            return None
        return near_box, far

    def screen_rect(self) -> pygame.Rect:
        return pygame.Rect((0, 0), self.camera.size)

    def _draw_prims(self, surf: pygame.Surface, prims: list, offset: tuple[float, float] | None = None) -> None:
        """Draw depth-sorted primitives; `offset` (pixels) is subtracted (drawing into a region)."""
        for _, kind, args in prims:
            if offset is not None:
                args = _shifted(kind, args, offset)
            if kind == 0:
                self._capsule(surf, *args)
            elif kind == 1:
                self._sphere(surf, *args)
            elif kind == 3:
                self._eyes(surf, *args)
            else:
                self._torso(surf, *args)

    def _draw_shadows(self, surf: pygame.Surface, bodies: list[np.ndarray]) -> None:
        cam = self.camera
        for joints in bodies:
            feet = joints[[J["ankle_l"], J["ankle_r"], J["pelvis"]]] * [1, 0, 1]
            xy = cam.project(feet.mean(axis=0) + SHADOW_RING)[0]
            lo, hi = xy.min(axis=0), xy.max(axis=0)
            size = (int(hi[0] - lo[0]) + 2, int(hi[1] - lo[1]) + 2)
            if size[0] <= 2 or size[1] <= 2 or size[0] > 4000 or size[1] > 4000:
                continue
            sh = pygame.Surface(size, pygame.SRCALPHA)
            self._poly(sh, (20, 10, 10, 90), xy - lo)
            surf.blit(sh, (int(lo[0]), int(lo[1])))

    def _boxer_prims(self, joints: np.ndarray, look: BoxerLook) -> list[tuple[float, int, tuple]]:
        cam = self.camera
        xy, z = cam.project(joints)
        scale = cam.scale_at(z)
        colors = {
            "skin": look.skin, "trunks_leg": look.trunks, "gloves": look.gloves, "shoes": look.shoes,
        }
        prims: list[tuple[float, int, tuple]] = []
        # the limbs and spheres from plain floats (one conversion per body, not numpy per limb)
        pts, zs, ks = xy.tolist(), z.tolist(), scale.tolist()
        for a, b, r, part in LIMBS:
            ia, ib = J[a], J[b]
            d = (zs[ia] + zs[ib]) / 2
            prims.append((d, 0, (pts[ia], pts[ib], r * ks[ia], r * ks[ib], colors[part])))
        # trunks legs: over the upper half of each thigh
        for hip, knee in (("hip_l", "knee_l"), ("hip_r", "knee_r")):
            ia, ib = J[hip], J[knee]
            (ax, ay), (bx, by) = pts[ia], pts[ib]
            mid_xy = (ax + (bx - ax) * 0.5, ay + (by - ay) * 0.5)
            d = (zs[ia] * 0.75 + zs[ib] * 0.25) - 0.01
            prims.append((d, 0, (pts[ia], mid_xy, 0.09 * ks[ia], 0.085 * ks[ib], look.trunks)))
        for name, r, part in SPHERES:
            i = J[name]
            prims.append((zs[i] - r, 1, (pts[i], r * ks[i], colors[part])))
        # the face: eyes and brows on the side of the head the boxer faces, drawn just after
        # the head when that side is towards the camera (so a boxer's facing reads at once)
        right = joints[J["shoulder_r"]] - joints[J["shoulder_l"]]
        right[1] = 0.0
        n = float(np.linalg.norm(right))
        if n > 1e-6:
            right /= n
            forward = facing(right)
            head = joints[J["head"]]
            eyes = np.array([head + forward * 0.11 + right * s + (0.0, 0.02, 0.0) for s in (-0.045, 0.045)])
            exy, ez = cam.project(eyes)
            if ez.mean() < z[J["head"]] - 0.03:
                prims.append((z[J["head"]] - 0.125 - 1e-4, 3, (exy, float(scale[J["head"]]))))
        # torso: chest block from shoulders to hips, trunks below the navel
        torso_ids = [J["shoulder_l"], J["shoulder_r"], J["hip_r"], J["hip_l"]]
        d = float(z[torso_ids].mean()) + 0.02
        prims.append((d, 2, (xy, scale, look)))
        return prims

    # Capsules and spheres are drawn from plain floats: at ~40 capsules a frame the small numpy
    # arrays per limb (difference, normal, quad, .tolist()) cost more than the drawing (issue 14).
    def _capsule(self, surf: pygame.Surface, a, b, ra: float, rb: float, color) -> None:
        ax, ay, bx, by = float(a[0]), float(a[1]), float(b[0]), float(b[1])
        outline = shade(color, 0.45)
        self._capsule_fill(surf, (ax, ay), (bx, by), ra + 1.5, rb + 1.5, outline)
        if self.antialias:  # smooth the silhouette: the outline's edges and end caps
            _capsule_edges(surf, (ax, ay), (bx, by), ra + 1.5, rb + 1.5, outline)
        self._capsule_fill(surf, (ax, ay), (bx, by), ra, rb, color)
        if not self.detailed:
            return
        # highlight: a thinner, lighter capsule shifted towards the light
        ox, oy = LIGHT_X * 0.35, LIGHT_Y * 0.35
        self._capsule_fill(surf, (ax + ox * ra, ay + oy * ra), (bx + ox * rb, by + oy * rb), ra * 0.45, rb * 0.45,
                           shade(color, 1.28))

    def _capsule_fill(self, surf: pygame.Surface, a, b, ra: float, rb: float, color) -> None:
        ax, ay, bx, by = float(a[0]), float(a[1]), float(b[0]), float(b[1])
        dx, dy = bx - ax, by - ay
        n = math.sqrt(dx * dx + dy * dy)
        if n > 1e-6:
            px, py = -dy / n, dx / n
            pygame.draw.polygon(surf, color, ((ax + px * ra, ay + py * ra), (bx + px * rb, by + py * rb),
                                              (bx - px * rb, by - py * rb), (ax - px * ra, ay - py * ra)))
        pygame.draw.circle(surf, color, (ax, ay), max(1.0, ra))
        pygame.draw.circle(surf, color, (bx, by), max(1.0, rb))

    def _eyes(self, surf: pygame.Surface, xy: np.ndarray, k: float) -> None:
        r = max(1.0, 0.014 * k)
        for x, y in xy:
            pygame.draw.circle(surf, (30, 24, 22), (float(x), float(y)), r)
            pygame.draw.line(surf, (50, 36, 30), (x - 2.2 * r, y - 2.2 * r), (x + 2.2 * r, y - 2.4 * r), max(1, int(r)))

    def _sphere(self, surf: pygame.Surface, c: np.ndarray, r: float, color) -> None:
        pos = (float(c[0]), float(c[1]))
        pygame.draw.circle(surf, shade(color, 0.45), pos, r + 1.5)
        if self.antialias:
            _aacircle(surf, shade(color, 0.45), pos[0], pos[1], r + 1.5)
        pygame.draw.circle(surf, shade(color, 0.8), pos, r)
        if not self.detailed:
            return
        pygame.draw.circle(surf, color, (pos[0] + LIGHT_X * r * 0.15, pos[1] + LIGHT_Y * r * 0.15), r * 0.8)
        pygame.draw.circle(surf, shade(color, 1.35), (pos[0] + LIGHT_X * r * 0.4, pos[1] + LIGHT_Y * r * 0.4), r * 0.3)

    def _torso(self, surf: pygame.Surface, xy: np.ndarray, scale: np.ndarray, look: BoxerLook) -> None:
        sl, sr, hl, hr = xy[J["shoulder_l"]], xy[J["shoulder_r"]], xy[J["hip_l"]], xy[J["hip_r"]]
        pel, chest = xy[J["pelvis"]], xy[J["chest"]]
        k = float(scale[J["chest"]])
        # widen the shoulder line and hips a little so the torso reads as a volume
        def widen(p: np.ndarray, q: np.ndarray, by: float) -> tuple[np.ndarray, np.ndarray]:
            mid, half = (p + q) / 2, (q - p) / 2
            n = float(np.hypot(*half))
            if n < 1e-6:
                half, n = np.array([1.0, 0.0]), 1.0
            return mid - half * (1 + by / n), mid + half * (1 + by / n)
        sl2, sr2 = widen(sl, sr, 0.07 * k)
        hl2, hr2 = widen(hl, hr, 0.05 * k)
        waist_l = sl2 + (hl2 - sl2) * 0.62
        waist_r = sr2 + (hr2 - sr2) * 0.62
        chest_poly = np.array([sl2, sr2, waist_r, waist_l])
        trunks_poly = np.array([waist_l, waist_r, hr2, pel + (hr2 - pel) * 0.2 + (pel - chest) * 0.12, hl2])
        skin, trunks = look.skin, look.trunks
        # the trunk's volume from any side: a capsule chest -> spine, the trunks round the pelvis
        spine, pelvis = xy[J["spine"]], xy[J["pelvis"]]
        self._capsule(surf, chest, spine, 0.15 * k, 0.14 * k, skin)
        self._capsule(surf, spine + (pelvis - spine) * 0.3, pelvis, 0.14 * k, 0.14 * k, trunks)
        self._poly(surf, shade(skin, 0.45), chest_poly, 0)
        self._poly(surf, shade(skin, 0.45), chest_poly, 3)
        inset = (chest_poly - chest_poly.mean(axis=0)) * 0.92 + chest_poly.mean(axis=0)
        self._poly(surf, skin, inset)
        hl_poly = (chest_poly - chest_poly.mean(axis=0)) * 0.45 + chest_poly.mean(axis=0) + LIGHT_2D * 0.06 * k
        self._poly(surf, shade(skin, 1.18), hl_poly)
        self._poly(surf, shade(trunks, 0.45), trunks_poly, 0)
        t_in = (trunks_poly - trunks_poly.mean(axis=0)) * 0.9 + trunks_poly.mean(axis=0)
        self._poly(surf, trunks, t_in)
        # waistband, where the hips face the camera enough to show it
        if float(np.hypot(*(waist_r - waist_l))) > 0.2 * k:
            pygame.draw.line(surf, (245, 245, 245), waist_l, waist_r, max(2, int(0.035 * k)))

    def _draw_flashes(self, surf: pygame.Surface) -> None:
        cam = self.camera
        for f in self.flashes:
            xy, z = cam.project(f.point[None, :])
            c = xy[0]
            life = 1.0 - f.age / Flash.LIFE
            r = float(cam.scale_at(z[0])) * (0.18 + 0.25 * (1 - life)) * (1.3 if f.strong else 0.8)
            ang = STAR_ANG + f.age * 0.15
            radii = STAR_RADII * r
            star = c + np.stack([np.cos(ang) * radii, np.sin(ang) * radii], axis=1)
            col = (150, 200, 255) if f.blocked else (255, 236, 120)
            self._poly(surf, col, star)
            pygame.draw.circle(surf, (255, 255, 255), (float(c[0]), float(c[1])), r * 0.35 * life + 1)
