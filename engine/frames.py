"""Samples to 60 Hz frames (ARCHITECTURE.md): a frame is one step's input vector of shape
(3 * sensors,), the sensors' accel at the step's instant, interpolated linearly between the
samples around it, or held from the last one when no later sample has arrived yet.

`resample` does a whole recording at once (numpy); `FrameResampler` does the same
step by step for live sources and gives identical values once the samples around an instant
are known.
"""

from __future__ import annotations

import numpy as np

from engine.recording import Recording
from engine.sensors.source import Sample

FRAME_HZ = 60


def frame_times(t0: float, t_end: float, hz: int = FRAME_HZ) -> np.ndarray:
    """The step grid t0 + k/hz covering [t0, t_end]; computed from k, so it never drifts."""
    n = int(np.floor((t_end - t0) * hz + 1e-9)) + 1
    return t0 + np.arange(n, dtype=np.float64) / hz


def resample(t: np.ndarray, accel: np.ndarray, hz: int = FRAME_HZ, mode: str = "linear") -> tuple[np.ndarray, np.ndarray]:
    """Resample (n,) times and (n, sensors, 3) or (n, D) values to the grid. Returns
    (grid_times, frames of shape (m, D)). `mode` is 'linear' or 'hold'."""
    t = np.asarray(t, dtype=np.float64)
    x = np.asarray(accel, dtype=np.float64).reshape(len(t), -1)
    grid = frame_times(float(t[0]), float(t[-1]), hz)
    if mode == "hold":
        idx = np.searchsorted(t, grid, side="right") - 1
        return grid, x[np.clip(idx, 0, len(t) - 1)]
    if mode != "linear":
        raise ValueError(f"mode must be 'linear' or 'hold', not {mode!r}")
    # np.interp per column; duplicate times are fine (interp takes the later value).
    frames = np.empty((len(grid), x.shape[1]), dtype=np.float64)
    for d in range(x.shape[1]):
        frames[:, d] = np.interp(grid, t, x[:, d])
    return grid, frames


def resample_labels(t: np.ndarray, labels: list[str], grid: np.ndarray) -> list[str]:
    """The label in force at each grid instant (the last sample at or before it)."""
    idx = np.clip(np.searchsorted(np.asarray(t), grid, side="right") - 1, 0, len(labels) - 1)
    return [labels[i] for i in idx]


def recording_frames(rec: Recording, hz: int = FRAME_HZ) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(grid times relative to the first sample, frames (m, 3*sensors), labels per frame)."""
    grid, frames = resample(rec.t, rec.accel, hz)
    return grid - rec.t[0], frames, resample_labels(rec.t, rec.labels, grid)


class FrameResampler:
    """Live resampling: push samples as sources deliver them, ask for the frame at a step's time.

    Keeps only the two samples around the last asked instant, so it allocates nothing per step
    beyond the output vector it reuses.
    """

    def __init__(self, sensors: int, mode: str = "linear"):
        self.dim = 3 * sensors
        self.mode = mode
        self._pending: list[Sample] = []
        self._prev_t = -np.inf
        self._prev = np.zeros(self.dim)
        self._have = False
        self._out = np.zeros(self.dim)

    def push(self, samples: list[Sample]) -> None:
        self._pending.extend(samples)

    def frame_at(self, t: float) -> np.ndarray | None:
        """The frame for instant t, or None before the first sample. The returned array is
        reused by the next call: copy it to keep it."""
        pending = self._pending
        i = 0
        while i < len(pending) and pending[i].t <= t:
            self._prev_t, self._prev = pending[i].t, np.asarray(pending[i].accel, dtype=np.float64).ravel()
            self._have = True
            i += 1
        del pending[:i]
        if not self._have:
            return None
        if self.mode == "linear" and pending and pending[0].t > self._prev_t:
            nxt = np.asarray(pending[0].accel, dtype=np.float64).ravel()
            w = (t - self._prev_t) / (pending[0].t - self._prev_t)
            np.multiply(self._prev, 1.0 - w, out=self._out)
            self._out += w * nxt
        else:
            self._out[:] = self._prev
        return self._out
