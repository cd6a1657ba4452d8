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
