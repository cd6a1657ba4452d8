"""Motion estimates beyond the paper (its future work): speed, direction and peak acceleration of
the hand since the onset, reported on `start` and `switch` events. DualBufferRecognizer owns one
(`self.speed`) and resets it at each motion's onset."""

from __future__ import annotations

import math

from engine.clock import STEP_HZ

G = 9.81


class SpeedEstimate:
    """A rough hand velocity integrated from the gravity-removed acceleration since the onset
    (plain floats: a few sensors a frame), with its peak speed, direction and acceleration."""

    def __init__(self, dim: int):
        self.dim = dim
        self.reset()

    def reset(self) -> None:
        """A new motion: nothing integrated yet."""
        self.velocity = [0.0] * self.dim
        self.peak_speed = 0.0
        self.peak_dir = [0.0, 0.0, 0.0]
        self.peak_g = 0.0

    def track(self, xs: list[float], g0: list[float]) -> None:
        """Integrate one frame (`xs`, gravity included) against the onset's gravity `g0`: enough
        to tell a hard punch from a soft one (the paper's future work)."""
        v = self.velocity
        k_dt = G / STEP_HZ
        peak_g, peak_speed = self.peak_g, self.peak_speed  # (locals: this runs every frame)
        for k in range(0, len(xs), 3):
            dx, dy, dz = xs[k] - g0[k], xs[k + 1] - g0[k + 1], xs[k + 2] - g0[k + 2]
            size = math.sqrt(dx * dx + dy * dy + dz * dz)
            if size > peak_g:
                peak_g = size
            vx, vy, vz = v[k] + dx * k_dt, v[k + 1] + dy * k_dt, v[k + 2] + dz * k_dt
            v[k], v[k + 1], v[k + 2] = vx, vy, vz
            sp = math.sqrt(vx * vx + vy * vy + vz * vz)
            if sp > peak_speed:
                peak_speed = sp
                self.peak_dir = [vx / sp, vy / sp, vz / sp]
        self.peak_g, self.peak_speed = peak_g, peak_speed
