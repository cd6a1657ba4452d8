"""Motion estimates beyond the paper (its future work): speed, direction and peak acceleration of
the hand since the onset, reported on `start` and `switch` events. Mixed into DualBufferRecognizer."""

from __future__ import annotations

import math

from engine.clock import STEP_HZ

G = 9.81


class SpeedEstimate:
    """A rough hand velocity integrated from the gravity-removed acceleration (plain floats)."""

    def _track_speed(self) -> None:
        """Integrate the gravity-removed acceleration since the onset: a rough hand velocity,
        enough to tell a hard punch from a soft one (the paper's future work). Plain floats."""
        xs, g0, v = self._xs, self._g0_list, self._velocity
        k_dt = G / STEP_HZ
        for k in range(0, len(xs), 3):
            dx, dy, dz = xs[k] - g0[k], xs[k + 1] - g0[k + 1], xs[k + 2] - g0[k + 2]
            self._peak_g = max(self._peak_g, math.sqrt(dx * dx + dy * dy + dz * dz))
            v[k] += dx * k_dt
            v[k + 1] += dy * k_dt
            v[k + 2] += dz * k_dt
            sp = math.sqrt(v[k] * v[k] + v[k + 1] * v[k + 1] + v[k + 2] * v[k + 2])
            if sp > self._peak_speed:
                self._peak_speed = sp
                self._peak_dir = [v[k] / sp, v[k + 1] / sp, v[k + 2] / sp]
