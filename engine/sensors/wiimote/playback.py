"""A recording played back at the emulated remote's 10 ms report slots: linear
interpolation between its samples, looping or holding its last value at the end."""

from __future__ import annotations

import numpy as np

from engine.recording import Recording


class RecordingPlayback:
    """`values_at(rel)`: (sensors, 3) in g at `rel` seconds into the recording."""

    def __init__(self, rec: Recording, default_period: float) -> None:
        self.sensors = rec.sensors
        self._rel = rec.t - rec.t[0]
        period = float(np.median(np.diff(self._rel))) if len(rec) > 1 else default_period
        self._length = float(self._rel[-1]) + period
        # (n, sensors*3) contiguous: a report looks up two rows, never copies a whole column
        self._values = np.ascontiguousarray(rec.accel.reshape(len(rec), -1), dtype=np.float64)

    def wrap(self, rel: float, loop: bool) -> float:
        """`rel` seconds in: modulo the length (one sample period after the last) when
        looping, else at most the last sample's time."""
        return rel % self._length if loop else min(rel, float(self._rel[-1]))

    def values_at(self, rel: float) -> np.ndarray:
        # np.interp's arithmetic on the two samples around rel, found by one binary search:
        # O(log n) per report (interp on the recording's columns copied them: O(n))
        xp, fp = self._rel, self._values
        j = int(np.searchsorted(xp, rel, side="right")) - 1
        if j < 0:
            g = fp[0].copy()
        elif j >= len(xp) - 1:
            g = fp[-1].copy()
        else:
            slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
            g = slope * (rel - xp[j]) + fp[j]
        return g.reshape(self.sensors, 3)
