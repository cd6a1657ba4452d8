"""Samples to 60 Hz frames (docs/engine.md, "Frames"): a frame is one step's input vector of shape
(3 * sensors,), the sensors' accel at the step's instant, interpolated linearly between the
samples around it, or held from the last one when no later sample has arrived yet.

`resample` does a whole recording at once (numpy); `FrameResampler` does the same
step by step for live sources and gives identical values once the samples around an instant
are known.
"""

from __future__ import annotations

import numpy as np

from engine.clock import STEP_HZ
from engine.recording import Recording
from engine.sample import Sample

FRAME_HZ = STEP_HZ


FLOAT_TOLERANCE = 1e-9  # of a frame: float error in a duration computed in memory
# of a frame: a recording FILE's times are written rounded (to 4 decimals in docs/formats.md's
# example, 6 by `record`), so its last sample at 0.0333 s is the step at 1/30 s; else a 60 Hz
# recording read back lost its last frame. 4 decimals are off by up to 0.003 frames.
WRITTEN_TOLERANCE = 0.005


def frame_offsets(duration: float, hz: int = FRAME_HZ, tolerance: float = FLOAT_TOLERANCE) -> np.ndarray:
    """k / hz for every step k in [0, duration]: computed from k, never summed, so frame k is
    exactly k/hz seconds after the first one; a last step `tolerance` frames past the duration
    still counts."""
    n = int(np.floor(duration * hz + tolerance)) + 1
    return np.arange(n, dtype=np.float64) / hz


def frame_times(t0: float, t_end: float, hz: int = FRAME_HZ, tolerance: float = FLOAT_TOLERANCE) -> np.ndarray:
    """The step grid t0 + k/hz covering [t0, t_end] (see frame_offsets)."""
    return t0 + frame_offsets(t_end - t0, hz, tolerance)


def interpolate_at(t: np.ndarray, x: np.ndarray, at: np.ndarray, mode: str = "linear") -> np.ndarray:
    """Values of samples (t (n,), x (n, D)) at instants `at`: linear between the last sample at
    or before the instant and the next one, held from the last one where no later sample
    exists (and from the first one before it). The arithmetic is the same as FrameResampler's,
    so live and offline frames agree to the bit."""
    if mode not in ("linear", "hold"):
        raise ValueError(f"mode must be 'linear' or 'hold', not {mode!r}")
    n = len(t)
    idx = np.clip(np.searchsorted(t, at, side="right") - 1, 0, n - 1)
    out = x[idx].copy()
    if mode == "hold" or n < 2:
        return out
    nxt = idx + 1
    inner = (nxt < n) & (at >= t[idx])
    inner[inner] &= t[nxt[inner]] > t[idx[inner]]
    i, j = idx[inner], nxt[inner]
    w = ((at[inner] - t[i]) / (t[j] - t[i]))[:, None]
    out[inner] = x[i] * (1.0 - w) + w * x[j]
    return out


def resample(t: np.ndarray, accel: np.ndarray, hz: int = FRAME_HZ, mode: str = "linear",
             tolerance: float = FLOAT_TOLERANCE) -> tuple[np.ndarray, np.ndarray]:
    """Resample (n,) times and (n, sensors, 3) or (n, D) values to the grid t[0] + k/hz.
    Returns (grid_times, frames of shape (m, D)). `mode` is 'linear' or 'hold'."""
    t = np.asarray(t, dtype=np.float64)
    x = np.asarray(accel, dtype=np.float64).reshape(len(t), -1)
    grid = frame_times(float(t[0]), float(t[-1]), hz, tolerance)
    return grid, interpolate_at(t, x, grid, mode)


def resample_labels(t: np.ndarray, labels: list[str], grid: np.ndarray) -> list[str]:
    """The label in force at each grid instant (the last sample at or before it)."""
    idx = np.clip(np.searchsorted(np.asarray(t), grid, side="right") - 1, 0, len(labels) - 1)
    return [labels[i] for i in idx]


def recording_frames(rec: Recording, hz: int = FRAME_HZ, phase: float = 0.0) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(grid times relative to the first sample, exactly (k + phase)/hz; frames (m, 3*sensors);
    labels per frame) of a recording as read from its file (its times rounded: WRITTEN_TOLERANCE).
    `phase` (0 <= phase < 1) moves the grid that fraction of a step later, to (k + phase)/hz: where a
    recording's first sample falls between two steps is chance, and the evaluation pools over it
    (`quickjab evaluate --phases`)."""
    if not 0.0 <= phase < 1.0:
        raise ValueError(f"phase must be a fraction of a step in [0, 1), not {phase!r}")
    t0 = float(rec.t[0]) + phase / hz
    offsets = frame_offsets(float(rec.t[-1]) - t0, hz, WRITTEN_TOLERANCE)
    grid = t0 + offsets
    frames = interpolate_at(np.asarray(rec.t, dtype=np.float64), np.asarray(rec.accel, dtype=np.float64).reshape(len(rec.t), -1), grid)
    return offsets + phase / hz, frames, resample_labels(rec.t, rec.labels, grid)


class FrameResampler:
    """Live resampling: push samples as sources deliver them, ask for the frame at a step's time.

    Keeps only the samples not yet passed, so it allocates little per step. A frame for an
    instant equals `resample`'s once the first sample after the instant has been pushed;
    before that it holds the last value. A live consumer that wants interpolated frames asks
    for an instant a little in the past (one sample period of latency): see docs/engine.md.

    A source whose sensor count changes mid-run (a serial board rebooting with one IMU fewer)
    says so by the shape of its samples. Frames keep this resampler's width: a missing sensor
    holds its last value, an extra one is left out, and `resized` counts those samples.
    """

    def __init__(self, sensors: int, mode: str = "linear"):
        self.dim = 3 * sensors
        self.mode = mode
        self._pending: list[Sample] = []
        self._prev_t = -np.inf
        self._prev = np.zeros(self.dim)
        self._have = False
        self._out = np.zeros(self.dim)
        self._tmp = np.zeros(self.dim)
        self.resized = 0

    def push(self, samples: list[Sample]) -> None:
        dim = self.dim
        for s in samples:
            if np.size(s.accel) != dim:
                self._pending.append(Sample(s.t, self._fit(s.accel)))
                self.resized += 1
            else:
                self._pending.append(s)

    def _fit(self, accel: np.ndarray) -> np.ndarray:
        """A sample of another width to this resampler's: sensors it lacks hold their last value."""
        flat = np.asarray(accel, dtype=np.float64).ravel()
        last = np.asarray(self._pending[-1].accel, dtype=np.float64).ravel() if self._pending else self._prev
        out = last.copy()
        k = min(flat.size, self.dim)
        out[:k] = flat[:k]
        return out

    def frame_at(self, t: float) -> np.ndarray | None:
        """The frame for instant t, or None before the first sample. The returned array is
        reused by the next call: copy it to keep it."""
        pending = self._pending
        n = len(pending)
        i = 0
        while i < n and pending[i].t <= t:
            i += 1
        if i:  # only the last sample passed matters: convert that one alone
            last = pending[i - 1]
            self._prev_t, self._prev = last.t, np.asarray(last.accel, dtype=np.float64).ravel()
            self._have = True
            del pending[:i]
        if not self._have:
            return None
        if self.mode == "linear" and pending and pending[0].t > self._prev_t:
            nxt = np.asarray(pending[0].accel, dtype=np.float64).ravel()
            w = (t - self._prev_t) / (pending[0].t - self._prev_t)
            # the same arithmetic as interpolate_at: x0 * (1 - w) + w * x1
            np.multiply(self._prev, 1.0 - w, out=self._out)
            np.multiply(nxt, w, out=self._tmp)
            self._out += self._tmp
        else:
            self._out[:] = self._prev
        return self._out
