"""A perspective camera that looks at the ring from three-quarters above: world points (metres,
y up) to screen pixels, with depth for painter's ordering. One numpy call per point array."""

from __future__ import annotations

import numpy as np

# Behind the player's right shoulder, raised: the classic three-quarter boxing-game view.
DEFAULT_EYE = (4.3, 2.8, -4.4)
DEFAULT_TARGET = (0.0, 0.85, 0.2)
DEFAULT_FOV_DEG = 38.0


class Camera:
    def __init__(self, size: tuple[int, int], eye=DEFAULT_EYE, target=DEFAULT_TARGET, fov_deg: float = DEFAULT_FOV_DEG):
        self.eye = np.asarray(eye, dtype=np.float64)
        self.target = np.asarray(target, dtype=np.float64)
        self.fov_deg = fov_deg
        forward = self.target - self.eye
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, (0.0, 1.0, 0.0))
        right /= np.linalg.norm(right)
        # The contract's frame has +x on a boxer's right when it faces +z with y up, so a view
        # along +z must show +x on the right: screen-right is -(forward x up).
        right = -right
        up = np.cross(forward, right)
        self._rot = np.stack([right, up, forward])  # rows: camera axes in world coords
        self.resize(size)

    def resize(self, size: tuple[int, int]) -> None:
        self.size = (int(size[0]), int(size[1]))
        w, h = self.size
        self.focal = 0.5 * h / np.tan(np.radians(self.fov_deg) / 2)
        self.centre = np.array([w / 2, h / 2])

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) world -> (..., 3) camera coordinates (x right, y up, z depth)."""
        return (np.asarray(points, dtype=np.float64) - self.eye) @ self._rot.T

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(..., 3) world -> ((..., 2) pixel coordinates, (...) depth in metres)."""
        c = self.to_camera(points)
        z = np.maximum(c[..., 2], 1e-3)
        xy = np.empty(c.shape[:-1] + (2,))
        xy[..., 0] = self.centre[0] + self.focal * c[..., 0] / z
        xy[..., 1] = self.centre[1] - self.focal * c[..., 1] / z
        return xy, z

    def scale_at(self, depth: np.ndarray | float) -> np.ndarray | float:
        """Pixels per metre at a depth."""
        return self.focal / np.maximum(depth, 1e-3)


# Two players (play --players 2): from the side of the ring, raised so the near ropes pass
# below the boxers' feet; the two stand left (player 1) and right (player 2) in profile and
# neither hides the other.
SIDE_ON_EYE = (5.6, 2.9, -0.5)
SIDE_ON_TARGET = (0.0, 0.95, 0.0)


SIDE_ON_HEADINGS = 8  # the side-on camera cuts between 8 views around the ring, 45 degrees apart
SIDE_ON_HYSTERESIS_DEG = 10.0  # past the half-way line by this much before it cuts


def side_on_camera(size: tuple[int, int], heading: int = 0) -> Camera:
    """The camera of a two-player match: the ring seen side-on, player 1 on the left, for
    boxers whose line (player 1 to player 2) points `heading` x 45 degrees from +z."""
    phi = 2.0 * np.pi * heading / SIDE_ON_HEADINGS
    c, s = np.cos(phi), np.sin(phi)

    def turn(p):  # about the vertical axis: +z goes to (sin phi, 0, cos phi)
        return (p[0] * c + p[2] * s, p[1], -p[0] * s + p[2] * c)

    return Camera(size, eye=turn(SIDE_ON_EYE), target=turn(SIDE_ON_TARGET))


def side_on_heading(p1: np.ndarray, p2: np.ndarray, current: int | None = None) -> int:
    """The view (0..7) that sees the line from p1 to p2 (world x, z) side-on. Keeps `current`
    until the line is SIDE_ON_HYSTERESIS_DEG past the half-way mark to the next view, so two
    boxers circling on the boundary do not make the camera flicker between two views."""
    dx, dz = float(p2[0] - p1[0]), float(p2[1] - p1[1])
    if dx * dx + dz * dz < 1e-6:
        return 0 if current is None else current
    step = 360.0 / SIDE_ON_HEADINGS
    phi = np.degrees(np.arctan2(dx, dz))
    if current is not None:
        off = (phi - current * step + 180.0) % 360.0 - 180.0
        if abs(off) < step / 2 + SIDE_ON_HYSTERESIS_DEG:
            return current
    return int(round(phi / step)) % SIDE_ON_HEADINGS
